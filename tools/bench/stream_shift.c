// Two passes per round over two arrays of N doubles, each thread on its own half
// (MODE 0) or, in the second pass, on halves shifted by N/4 (MODE 1), so that half of what
// a thread reads was last written by the other core (BENCHMARKS.md, ninth sitting).
//   gcc -O2 -fopenmp tools/bench/stream_shift.c -o /tmp/shift
//   for m in 0 1; do for t in 1 2; do OMP_NUM_THREADS=$t /tmp/shift 2500000 80 $m; done; done
#include <stdio.h>
#include <stdlib.h>
#include <omp.h>
// Two passes per round over arrays of n doubles, both writing. Mode 0: each thread always
// owns the same half. Mode 1: the second pass's halves are shifted by n/4, so half of what a
// thread reads was last written by the other thread.
int main(int argc,char**argv){ long n=atol(argv[1]); int reps=atoi(argv[2]); int mode=atoi(argv[3]);
 double *a=malloc(n*8),*b=malloc(n*8);
 for(long i=0;i<n;i++){a[i]=1;b[i]=2;}
 int T=omp_get_max_threads();
 double t=omp_get_wtime();
 for(int r=0;r<reps;r++){
 #pragma omp parallel
 { int k=omp_get_thread_num(); long lo=n*k/T, hi=n*(k+1)/T;
   for(long i=lo;i<hi;i++) a[i]=a[i]*0.999+b[i];
   #pragma omp barrier
   long s = mode? n/4 : 0;
   for(long q=lo;q<hi;q++){ long i=(q+s)%n; b[i]=b[i]*0.999+a[i]; }
 }
 }
 t=omp_get_wtime()-t; printf("n=%ld T=%d mode=%d  ns/elem/pass=%.3f\n",n,T,mode,t/reps/n/2*1e9); return a[5]>0?0:1;}
