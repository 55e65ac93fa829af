// Throughput of square roots and divisions on this machine, scalar and packed
// (BENCHMARKS.md, fourteenth sitting): eight independent chains, so the unit's throughput,
// not one operation's latency, sets the time.
//   gcc -O2 -fno-tree-vectorize -fno-math-errno tools/bench/divider.c -o /tmp/divider -lm && /tmp/divider
// (-fno-tree-vectorize keeps the scalar loops scalar; the packed ones use SSE2 intrinsics.)
#include <math.h>
#include <stdio.h>
#include <time.h>
#include <emmintrin.h>
static double now(void){ struct timespec t; clock_gettime(CLOCK_MONOTONIC,&t); return t.tv_sec+1e-9*t.tv_nsec; }
int main(void){
  const long n = 400000000L; double a[8], t; __m128d p[4];
  for(int k=0;k<8;k++) a[k]=1.1+0.1*k;
  t=now(); for(long i=0;i<n/8;i++) for(int k=0;k<8;k++) a[k]=sqrt(a[k]+1.0);
  printf("sqrtsd: %.2f ns per root (%g)\n",(now()-t)*1e9/n,a[0]+a[7]);
  t=now(); for(long i=0;i<n/8;i++) for(int k=0;k<8;k++) a[k]=1.0/(a[k]+1.0);
  printf("divsd:  %.2f ns per division (%g)\n",(now()-t)*1e9/n,a[0]+a[7]);
  for(int k=0;k<4;k++) p[k]=_mm_set_pd(1.1+0.1*k,1.5+0.1*k);
  __m128d one=_mm_set1_pd(1.0);
  t=now(); for(long i=0;i<n/8;i++) for(int k=0;k<4;k++) p[k]=_mm_sqrt_pd(_mm_add_pd(p[k],one));
  printf("sqrtpd: %.2f ns per root, two per instruction (%g)\n",(now()-t)*1e9/n,_mm_cvtsd_f64(p[0]));
  t=now(); for(long i=0;i<n/8;i++) for(int k=0;k<4;k++) p[k]=_mm_div_pd(one,_mm_add_pd(p[k],one));
  printf("divpd:  %.2f ns per division, two per instruction (%g)\n",(now()-t)*1e9/n,_mm_cvtsd_f64(p[0]));
  return 0;
}
