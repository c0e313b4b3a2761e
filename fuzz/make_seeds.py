#!/usr/bin/env python3
"""Writes the seed corpora of the cota fuzz targets (fuzz/corpus/<target>/seed-*).

Every seed is a tiny hand-made file, valid or deliberately broken, built from
the format specifications with the standard library only (struct, zlib,
zipfile): no third-party data. Run from anywhere: python3 fuzz/make_seeds.py
"""

import io
import os
import struct
import zipfile
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def put(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "seed-" + name), "wb") as f:
        f.write(data)


# --- SRTM: n×n big-endian int16, void -32768 ---------------------------------

def hgt(values):
    return struct.pack(">%dh" % len(values), *values)


def zipped(members, method=zipfile.ZIP_DEFLATED):
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", method) as z:
        for name, data in members:
            z.writestr(name, data)
    return buf.getvalue()


def srtm():
    t3 = hgt([1, 2, 3, -4, -32768, 6, 7, 8, 9])
    put("read_srtm", "3x3.hgt", t3)
    put("read_srtm", "2x2-void.hgt", hgt([-32768, 0, 32767, -1]))
    put("read_srtm", "odd-7-bytes.hgt", b"\x00\x01\x02\x03\x04\x05\x06")
    put("read_srtm", "3x3.hgt.zip", zipped([("N10E010.hgt", t3)]))
    put("read_srtm", "stored.hgt.zip", zipped([("a/S01W001.HGT", hgt([5] * 4))], zipfile.ZIP_STORED))
    put("read_srtm", "no-hgt.zip", zipped([("readme.txt", b"hello")]))
    put("read_srtm", "two-hgt.zip", zipped([("a.hgt", t3), ("b.hgt", t3)]))
    put("read_srtm", "wrong-size-member.zip", zipped([("N00E000.hgt", b"\x00" * 10)]))


# --- ESRI ASCII ---------------------------------------------------------------

def asc():
    head = b"ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\n"
    put("read_asc", "corner.asc", head + b"NODATA_value -9999\n1 2 3\n4 -9999 6\n")
    put("read_asc", "center-float.asc",
        b"NCOLS 2\r\nNROWS 2\r\nXLLCENTER 1.5\r\nYLLCENTER -2\r\nCELLSIZE 0.5\r\n1.5 2e1\r\n-3.25 nan\r\n")
    put("read_asc", "dxdy.asc", b"ncols 1 nrows 2 xllcorner 0 yllcorner 0 dx 2 dy 3 7 8")
    put("read_asc", "short.asc", head + b"1 2 3\n4\n")
    put("read_asc", "long.asc", head + b"1 2 3 4 5 6 7\n")
    put("read_asc", "word.asc", head + b"1 2 x 4 5 6\n")
    put("read_asc", "huge-header.asc", b"ncols 100000000\nnrows 100000000\nxllcorner 0\nyllcorner 0\ncellsize 1\n1\n")
    put("read_asc", "no-cellsize.asc", b"ncols 1\nnrows 1\nxllcorner 0\nyllcorner 0\n1\n")


# --- PNG -----------------------------------------------------------------------

def chunk(kind, data):
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


def png(width, height, color_type, depth, rows, extra=b""):
    """rows: list of bytes, one per row, without the filter byte."""
    raw = b"".join(b"\x00" + r for r in rows)
    ihdr = struct.pack(">IIBBBBB", width, height, depth, color_type, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + extra
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def terrain_rgb(h):
    v = round((h + 10000) * 10)
    return bytes([v >> 16 & 255, v >> 8 & 255, v & 255])


def pngs():
    rgb_rows = [terrain_rgb(0) + terrain_rgb(1), terrain_rgb(100) + terrain_rgb(3776)]
    put("read_png", "terrain-rgb-2x2.png", png(2, 2, 2, 8, rgb_rows))
    put("read_png", "rgba-alpha0.png", png(2, 1, 6, 8, [terrain_rgb(5) + b"\x00" + terrain_rgb(6) + b"\xff"]))
    put("read_png", "gray16.png", png(2, 2, 0, 16, [b"\x00\x00\xff\xff", b"\x01\x00\x00\x01"]))
    put("read_png", "gray8.png", png(3, 1, 0, 8, [b"\x00\x80\xff"]))
    put("read_png", "gray-alpha.png", png(1, 1, 4, 8, [b"\x10\x00"]))
    put("read_png", "rgb-trns.png", png(1, 1, 2, 8, [b"\x01\x02\x03"], chunk(b"tRNS", b"\x00\x01\x00\x02\x00\x03")))
    put("read_png", "palette.png", png(1, 1, 3, 8, [b"\x00"], chunk(b"PLTE", b"\x01\x02\x03")))
    put("read_png", "huge-ihdr.png",
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 40000, 40000, 8, 2, 0, 0, 0)) + chunk(b"IEND", b""))
    good = png(2, 2, 2, 8, rgb_rows)
    put("read_png", "truncated.png", good[: len(good) - 20])


# --- TIFF / GeoTIFF --------------------------------------------------------------

def tiff(endian, width, height, sample_format, bits, pixels, geo=True, nodata=None):
    """A one-strip, uncompressed, single-band (Geo)TIFF."""
    e = "<" if endian == "II" else ">"
    header_len = 8
    data = pixels
    entries = []  # (tag, type, count, value bytes)

    def short(tag, v):
        entries.append((tag, 3, 1, struct.pack(e + "H", v) + b"\x00\x00"))

    def long_(tag, v):
        entries.append((tag, 4, 1, struct.pack(e + "I", v)))

    extra = []  # out-of-line values: (tag, type, count, bytes)

    def array(tag, typ, fmt, values):
        extra.append((tag, typ, len(values), struct.pack(e + fmt * len(values), *values)))

    short(256, width)
    short(257, height)
    short(258, bits)
    short(259, 1)  # no compression
    short(262, 1)  # min-is-black
    long_(273, 0)  # strip offset, patched below
    short(277, 1)
    long_(278, height)
    long_(279, len(data))
    short(339, sample_format)
    if geo:
        array(33550, 12, "d", [1 / 1200, 1 / 1200, 0.0])  # ModelPixelScale
        array(33922, 12, "d", [0, 0, 0, 10.0, 1.0, 0.0])  # ModelTiepoint
        # GeoKeyDirectory: version 1.1.0, 3 keys: model type geographic,
        # raster type pixel-is-point, geographic type EPSG:4326.
        array(34735, 3, "H", [1, 1, 0, 3, 1024, 0, 1, 2, 1025, 0, 1, 2, 2048, 0, 1, 4326])
    if nodata is not None:
        s = nodata.encode() + b"\x00"
        extra.append((42113, 2, len(s), s))
    n = len(entries) + len(extra)
    ifd_len = 2 + 12 * n + 4
    cursor = header_len + ifd_len
    blobs = b""
    all_entries = []
    for tag, typ, count, value in entries:
        all_entries.append((tag, typ, count, value))
    for tag, typ, count, value in extra:
        if len(value) <= 4:
            all_entries.append((tag, typ, count, value.ljust(4, b"\x00")))
        else:
            all_entries.append((tag, typ, count, struct.pack(e + "I", cursor + len(blobs))))
            blobs += value
            if len(blobs) % 2:
                blobs += b"\x00"
    strip_offset = cursor + len(blobs)
    all_entries.sort(key=lambda t: t[0])
    ifd = struct.pack(e + "H", n)
    for tag, typ, count, value in all_entries:
        if tag == 273:
            value = struct.pack(e + "I", strip_offset)
        ifd += struct.pack(e + "HHI", tag, typ, count) + value
    ifd += struct.pack(e + "I", 0)
    magic = b"II*\x00" if endian == "II" else b"MM\x00*"
    return magic + struct.pack(e + "I", header_len) + ifd + blobs + data


def tiffs():
    i16 = struct.pack("<4h", 100, -32768, 250, 7)
    put("read_geotiff", "i16-le-geo.tif", tiff("II", 2, 2, 2, 16, i16, nodata="-32768"))
    f32 = struct.pack(">4f", 1.5, 2.5, -3.0, 4.0)
    put("read_geotiff", "f32-be-geo.tif", tiff("MM", 2, 2, 3, 32, f32))
    u8 = bytes([0, 1, 2, 3, 4, 5])
    put("read_geotiff", "u8-plain.tif", tiff("II", 3, 2, 1, 8, u8, geo=False))
    good = tiff("II", 2, 2, 2, 16, i16, nodata="-32768")
    put("read_geotiff", "truncated.tif", good[:60])


if __name__ == "__main__":
    srtm()
    asc()
    pngs()
    tiffs()
