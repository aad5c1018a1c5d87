/* What one AVX-512VL scatter of 8 floats costs, with 8, 2, 1 and 0 lanes on (2026-11-29,
 * the 2-core AMD EPYC of BENCHMARKS.md). `gcc -O2 -mavx512f -mavx512vl scatter-mask.c &&
 * ./a.out` (output: scatter-mask.log). */
#include <immintrin.h>
#include <stdio.h>
#include <time.h>
static double now(){struct timespec t;clock_gettime(CLOCK_MONOTONIC,&t);return t.tv_sec+t.tv_nsec*1e-9;}
float buf[1<<17];
int main(){
  __m256i idx=_mm256_setr_epi32(3,1000,2000,3000,4000,5000,6000,7000);
  int masks[]={0xff,0x03,0x01,0x00};
  for(int mi=0;mi<4;mi++){
    __mmask8 m=masks[mi];
    __m256 v=_mm256_set1_ps(1.0f);
    double t=now(); long N=50000000;
    for(long i=0;i<N;i++){
      __m256i j=_mm256_add_epi32(idx,_mm256_set1_epi32((i*16)&0xffff));
      _mm256_mask_i32scatter_ps(buf,m,j,v,4);
      _mm256_mask_i32scatter_ps(buf+8,m,j,v,4);
      v=_mm256_add_ps(v,_mm256_set1_ps(1.0f));
    }
    t=now()-t;
    printf("scatter mask %02x: %.2f ns per scatter (%f)\n",masks[mi],t/N/2*1e9,buf[3]);
  }
}
