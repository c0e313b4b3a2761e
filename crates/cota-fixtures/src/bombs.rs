//! Hostile inputs for the memory-budget tests, written streaming into a file
//! (never committed, never held in memory): a gzip bomb of zeros and a PNG
//! dimension bomb. Both are made from DEFLATE blocks of zeros cut by a full
//! flush: after one, the compressor starts afresh (no back-reference crosses
//! it), so one compressed block of a chunk of zeros can be repeated to make a
//! stream of any length without compressing it all.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

use flate2::{Compress, Compression, FlushCompress};

/// Zeros per repeated DEFLATE block.
const CHUNK: usize = 1 << 20;

/// Raw DEFLATE pieces: the first block, the block repeated after it, the final
/// (empty) block; each ends byte-aligned.
struct Pieces {
    first: Vec<u8>,
    repeated: Vec<u8>,
    last: Vec<u8>,
}

/// Compresses blocks of `CHUNK` zeros at `level`.
fn pieces(level: u32) -> io::Result<Pieces> {
    let zeros = vec![0u8; CHUNK];
    let mut c = Compress::new(Compression::new(level), false);
    let mut block = |input: &[u8], flush| -> io::Result<Vec<u8>> {
        let mut out = Vec::with_capacity(CHUNK + 1024);
        c.compress_vec(input, &mut out, flush)
            .map_err(io::Error::other)?;
        Ok(out)
    };
    let first = block(&zeros, FlushCompress::Full)?;
    let repeated = block(&zeros, FlushCompress::Full)?;
    let again = block(&zeros, FlushCompress::Full)?;
    let last = block(&[], FlushCompress::Finish)?;
    if again != repeated {
        return Err(io::Error::other("the compressor's flushed blocks differ"));
    }
    Ok(Pieces {
        first,
        repeated,
        last,
    })
}

/// Writes `pieces` for `chunks` chunks of zeros (at least 1).
fn write_deflate(w: &mut impl Write, p: &Pieces, chunks: u64) -> io::Result<()> {
    w.write_all(&p.first)?;
    for _ in 1..chunks {
        w.write_all(&p.repeated)?;
    }
    w.write_all(&p.last)
}

/// Writes a gzip file (one member) that expands to `gib` GiB of zeros, at
/// DEFLATE `level` (1 gives about 4.5 MB per GiB; 9 about 1 MB). The
/// trailer's CRC is left 0 (a reader that checks it reads all first).
///
/// # Errors
/// The file cannot be written.
pub fn gzip_zeros(path: &Path, gib: u64, level: u32) -> io::Result<()> {
    let p = pieces(level)?;
    let mut w = BufWriter::new(File::create(path)?);
    w.write_all(&[0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 255])?;
    write_deflate(&mut w, &p, gib * 1024)?;
    w.write_all(&0u32.to_le_bytes())?;
    w.write_all(&((gib << 30) as u32).to_le_bytes())?;
    w.flush()
}

/// Writes a valid 16-bit gray PNG of `side`² zeros, padded with a private
/// ancillary chunk to `pad_to` bytes (so the file is large enough for its
/// pixels at DEFLATE's largest ratio).
///
/// # Errors
/// The file cannot be written.
pub fn png_gray16_zeros(path: &Path, side: u32, pad_to: usize) -> io::Result<()> {
    let p = pieces(9)?;
    let raw = u64::from(side) * (1 + 2 * u64::from(side));
    let chunks = raw.div_ceil(CHUNK as u64);
    let mut idat = vec![0x78, 0xda];
    write_deflate(&mut idat, &p, chunks)?;
    // Adler-32 of zeros: a = 1, b = count mod 65521 (the stream holds whole chunks).
    let b = (chunks * CHUNK as u64 % 65521) as u32;
    idat.extend_from_slice(&((b << 16) | 1).to_be_bytes());
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&side.to_be_bytes());
    ihdr.extend_from_slice(&side.to_be_bytes());
    ihdr.extend_from_slice(&[16, 0, 0, 0, 0]);
    let mut w = BufWriter::new(File::create(path)?);
    w.write_all(b"\x89PNG\r\n\x1a\n")?;
    chunk(&mut w, b"IHDR", &ihdr)?;
    let used = 8 + 25 + 12 + idat.len() + 12;
    let pad = pad_to.saturating_sub(used + 12);
    chunk(&mut w, b"prVt", &vec![0u8; pad])?;
    chunk(&mut w, b"IDAT", &idat)?;
    chunk(&mut w, b"IEND", &[])?;
    w.flush()
}

/// One PNG chunk: length, type, data, CRC-32 of type and data.
fn chunk(w: &mut impl Write, kind: &[u8; 4], data: &[u8]) -> io::Result<()> {
    let len = u32::try_from(data.len()).map_err(io::Error::other)?;
    w.write_all(&len.to_be_bytes())?;
    w.write_all(kind)?;
    w.write_all(data)?;
    let mut crc = flate2::Crc::new();
    crc.update(kind);
    crc.update(data);
    w.write_all(&crc.sum().to_be_bytes())
}
