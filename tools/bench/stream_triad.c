// Memory bandwidth on this machine, 1 and 2 threads (BENCHMARKS.md, ninth sitting):
// a[i] = b[i] + s c[i] over three arrays of N doubles, REPS times.
//   gcc -O2 -fopenmp tools/bench/stream_triad.c -o /tmp/triad
//   for n in 100000 1000000 8000000; do for t in 1 2; do OMP_NUM_THREADS=$t /tmp/triad $n $((400000000/n)); done; done
#include <stdio.h>
#include <stdlib.h>
#include <omp.h>
int main(int argc,char**argv){ long n=atol(argv[1]); int reps=atoi(argv[2]);
 double *a=malloc(n*8),*b=malloc(n*8),*c=malloc(n*8);
 #pragma omp parallel for
 for(long i=0;i<n;i++){a[i]=1;b[i]=2;c[i]=3;}
 double t=omp_get_wtime();
 for(int r=0;r<reps;r++){
 #pragma omp parallel for
 for(long i=0;i<n;i++) a[i]=b[i]+1.0001*c[i];
 }
 t=omp_get_wtime()-t; printf("n=%ld threads=%d GB/s=%.1f\n",n,omp_get_max_threads(),3.0*8*n*reps/t/1e9); return a[5]>0?0:1;}
