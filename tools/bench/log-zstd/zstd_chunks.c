// Compresses a file in independent pieces of `chunk` bytes with the given zstd parameters (one
// ZSTD_compress2 call per piece, or streamed in 600-byte writes) and prints the total compressed size.
// Built and run by run.sh (docs/performance.md, "The log's compression").
#define ZSTD_STATIC_LINKING_ONLY
#include <zstd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
// usage: zt file chunk level [lit(0 auto,1 huf,2 raw)] [windowLog] [hashLog] [minMatch] [targetLength] [stream]
int main(int argc, char**argv){
  FILE*f=fopen(argv[1],"rb"); fseek(f,0,SEEK_END); long n=ftell(f); fseek(f,0,SEEK_SET);
  char*buf=malloc(n); fread(buf,1,n,f); fclose(f);
  long chunk=atol(argv[2]); int level=atoi(argv[3]);
  int lit=argc>4?atoi(argv[4]):0, wl=argc>5?atoi(argv[5]):0, hl=argc>6?atoi(argv[6]):0, mm=argc>7?atoi(argv[7]):0, tl=argc>8?atoi(argv[8]):-1;
  int stream=argc>9?atoi(argv[9]):0;
  ZSTD_CCtx*c=ZSTD_createCCtx();
  size_t cap=ZSTD_compressBound(chunk+100000); char*out=malloc(cap);
  long tot=0;
  for(long off=0; off<n; off+=chunk){
    long len = n-off<chunk? n-off: chunk;
    ZSTD_CCtx_reset(c, ZSTD_reset_session_and_parameters);
    ZSTD_CCtx_setParameter(c, ZSTD_c_compressionLevel, level);
    if(lit) ZSTD_CCtx_setParameter(c, ZSTD_c_literalCompressionMode, lit==1?ZSTD_ps_enable:ZSTD_ps_disable);
    if(wl) ZSTD_CCtx_setParameter(c, ZSTD_c_windowLog, wl);
    if(hl) ZSTD_CCtx_setParameter(c, ZSTD_c_hashLog, hl);
    if(mm) ZSTD_CCtx_setParameter(c, ZSTD_c_minMatch, mm);
    if(tl>=0) ZSTD_CCtx_setParameter(c, ZSTD_c_targetLength, tl);
    size_t r;
    if(!stream){ r=ZSTD_compress2(c,out,cap,buf+off,len);}
    else { ZSTD_outBuffer ob={out,cap,0}; ZSTD_inBuffer ib={buf+off,len,0};
      // feed in 600-byte pieces like messages
      size_t p=0; while(p<len){ size_t k=len-p<600?len-p:600; ZSTD_inBuffer ii={buf+off+p,k,0}; ZSTD_compressStream2(c,&ob,&ii,ZSTD_e_continue); p+=k;}
      while(ZSTD_compressStream2(c,&ob,&(ZSTD_inBuffer){0,0,0},ZSTD_e_end)); r=ob.pos; }
    if(ZSTD_isError(r)){fprintf(stderr,"err %s\n",ZSTD_getErrorName(r));return 1;}
    tot+=r;
  }
  printf("in %ld out %ld ratio %.4f\n", n, tot, (double)n/tot);
  return 0;
}
