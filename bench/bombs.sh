#!/usr/bin/env bash
# Issue 23: peak memory and time of `cota info` on a gzip bomb (8 GiB of zeros
# in a 37 MB .hgt.gz) and a PNG dimension bomb (46340² gray16, 4.25 MB).
# The bombs are written streaming into a temporary directory (never committed).
# Usage: bash bench/bombs.sh [path/to/cota]   (default: target/release/cota)
set -euo pipefail
cota=${1:-target/release/cota}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
python3 - "$dir" <<'PY'
import struct, sys, zlib
d = sys.argv[1]
chunk = bytes(1 << 20)
def pieces(level):
    c = zlib.compressobj(level, zlib.DEFLATED, -15)
    first = c.compress(chunk) + c.flush(zlib.Z_FULL_FLUSH)
    rep = c.compress(chunk) + c.flush(zlib.Z_FULL_FLUSH)
    again = c.compress(chunk) + c.flush(zlib.Z_FULL_FLUSH)
    assert rep == again
    return first, rep, c.flush(zlib.Z_FINISH)
# gzip: 8 GiB of zeros at level 1, one member (CRC left 0).
first, rep, last = pieces(1)
with open(f"{d}/N10E010.hgt.gz", "wb") as f:
    f.write(bytes([0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 255]) + first)
    for _ in range(8 * 1024 - 1):
        f.write(rep)
    f.write(last + struct.pack("<II", 0, 0))
# PNG: 46340² gray16 zeros, padded to 4.25 MB.
side = 46340
first, rep, last = pieces(9)
n = -(-side * (1 + 2 * side) // len(chunk))
idat = b"\x78\xda" + first + rep * (n - 1) + last + struct.pack(">I", ((n * len(chunk) % 65521) << 16) | 1)
def chunk_(k, data):
    return struct.pack(">I", len(data)) + k + data + struct.pack(">I", zlib.crc32(k + data))
ihdr = struct.pack(">IIBBBBB", side, side, 16, 0, 0, 0, 0)
pad = 4_250_000 - (8 + 25 + 12 + len(idat) + 12 + 12)
with open(f"{d}/bomb.png", "wb") as f:
    f.write(b"\x89PNG\r\n\x1a\n" + chunk_(b"IHDR", ihdr) + chunk_(b"prVt", bytes(max(pad, 0))) + chunk_(b"IDAT", idat) + chunk_(b"IEND", b""))
PY
for f in "$dir/N10E010.hgt.gz" "$dir/bomb.png"; do
  size=$(stat -c %s "$f")
  /usr/bin/time -f "%e s %M KB exit=%x" -o "$dir/time" "$cota" info "$f" >/dev/null 2>"$dir/err" || true
  printf '%s (%s bytes): %s\n  %s\n' "$(basename "$f")" "$size" "$(cat "$dir/time" | tail -1)" "$(tail -1 "$dir/err")"
done
