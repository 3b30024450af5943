"""Writes the decompressed records of every chunk of an MCAP file, concatenated, and prints the chunk
count, the uncompressed and compressed bytes and their ratio. Usage: extract_chunks.py LOG.mcap OUT.bin"""
import sys, zstandard
from mcap.stream_reader import StreamReader
from mcap.records import Chunk
d = zstandard.ZstdDecompressor()
n=0; tot=0; comp=0
out = open(sys.argv[2], 'wb')
for r in StreamReader(open(sys.argv[1],"rb"), skip_magic=False, emit_chunks=True).records:
    if isinstance(r, Chunk):
        raw = d.decompress(r.data, max_output_size=r.uncompressed_size)
        out.write(raw); n+=1; tot+=len(raw); comp+=len(r.data)
print(n, tot, comp, tot/comp)
