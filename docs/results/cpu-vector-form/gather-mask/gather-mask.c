/* What one AVX2 gather of 8 floats costs, with 8, 2, 1 and 0 lanes on (2026-11-29, the
 * 2-core AMD EPYC of BENCHMARKS.md): a chain of dependent gathers, then four independent
 * ones per step. `gcc -O2 -mavx2 gather-mask.c && ./a.out` (output: gather-mask.log). */
#include <immintrin.h>
#include <stdio.h>
#include <time.h>
static double now(){struct timespec t;clock_gettime(CLOCK_MONOTONIC,&t);return t.tv_sec+t.tv_nsec*1e-9;}
float buf[1<<16];
int main(){
  for(int i=0;i<(1<<16);i++) buf[i]=i;
  __m256i idx=_mm256_setr_epi32(3,1000,2000,3000,4000,5000,6000,7000);
  int masks[]={0xff,0x03,0x01,0x00};
  for(int mi=0;mi<4;mi++){
    __m256 m=_mm256_castsi256_ps(_mm256_setr_epi32(masks[mi]&1?-1:0,masks[mi]&2?-1:0,masks[mi]&4?-1:0,masks[mi]&8?-1:0,masks[mi]&16?-1:0,masks[mi]&32?-1:0,masks[mi]&64?-1:0,masks[mi]&128?-1:0));
    __m256 acc=_mm256_setzero_ps();
    double t=now(); long N=100000000;
    for(long i=0;i<N;i++){
      __m256 g=_mm256_mask_i32gather_ps(acc,buf,idx,m,4);
      acc=_mm256_add_ps(acc,g); idx=_mm256_add_epi32(idx,_mm256_set1_epi32(1)); idx=_mm256_and_si256(idx,_mm256_set1_epi32(0x7fff));
    }
    t=now()-t; float o[8]; _mm256_storeu_ps(o,acc);
    printf("mask %02x: %.2f ns per gather (%f)\n",masks[mi],t/N*1e9,o[0]);
  }
  /* independent gathers: throughput */
  for(int mi=0;mi<4;mi++){
    __m256 m=_mm256_castsi256_ps(_mm256_setr_epi32(masks[mi]&1?-1:0,masks[mi]&2?-1:0,masks[mi]&4?-1:0,masks[mi]&8?-1:0,masks[mi]&16?-1:0,masks[mi]&32?-1:0,masks[mi]&64?-1:0,masks[mi]&128?-1:0));
    __m256 a0=_mm256_setzero_ps(),a1=a0,a2=a0,a3=a0;
    double t=now(); long N=50000000;
    for(long i=0;i<N;i++){
      __m256i j=_mm256_add_epi32(idx,_mm256_set1_epi32(i&1023));
      a0=_mm256_add_ps(a0,_mm256_mask_i32gather_ps(_mm256_setzero_ps(),buf,j,m,4));
      a1=_mm256_add_ps(a1,_mm256_mask_i32gather_ps(_mm256_setzero_ps(),buf+8,j,m,4));
      a2=_mm256_add_ps(a2,_mm256_mask_i32gather_ps(_mm256_setzero_ps(),buf+16,j,m,4));
      a3=_mm256_add_ps(a3,_mm256_mask_i32gather_ps(_mm256_setzero_ps(),buf+24,j,m,4));
    }
    t=now()-t; float o[8]; _mm256_storeu_ps(o,_mm256_add_ps(_mm256_add_ps(a0,a1),_mm256_add_ps(a2,a3)));
    printf("throughput mask %02x: %.2f ns per gather (%f)\n",masks[mi],t/N/4*1e9,o[0]);
  }
}
