//! Encoding in parallel, writing in order.
//!
//! [`write_chunks`] cuts a slice of records (vertices, triangles) into chunks,
//! encodes a batch of chunks on rayon's pool, each into its own byte buffer,
//! then writes the buffers in order, and goes on with the next batch. The
//! output is the bytes a sequential loop over the records would write; memory
//! is bounded by one batch of encoded bytes (a few chunks per thread), not by
//! the file.

use std::io::Write;

use rayon::prelude::*;

use super::error::ExportError;

/// Records per chunk: large enough that a chunk's encoding outweighs its
/// scheduling, small enough that a batch stays a few MB.
const CHUNK_RECORDS: usize = 1 << 14;

/// Chunks per batch and thread: work for a thread that finishes early.
const CHUNKS_PER_THREAD: usize = 4;

/// Writes `records` to `w` as `encode(first, chunk, buf)` turns each chunk of
/// them into bytes (`first` is the index of the chunk's first record in
/// `records`; bytes are appended to `buf`), chunks encoded in parallel and
/// written in order. `bytes_per_record` sizes the buffers (a hint).
///
/// One batch is written while the next is encoded (two sets of buffers), so
/// the copy into the file overlaps the encoding.
///
/// # Errors
/// [`ExportError::Io`] from `w`; the first error of `encode` in record order.
pub(crate) fn write_chunks<T, W, F>(
    w: &mut W,
    records: &[T],
    bytes_per_record: usize,
    encode: F,
) -> Result<(), ExportError>
where
    T: Sync,
    W: Write + Send + ?Sized,
    F: Fn(usize, &[T], &mut Vec<u8>) -> Result<(), ExportError> + Sync,
{
    write_chunks_of(w, records, CHUNK_RECORDS, bytes_per_record, encode)
}

/// [`write_chunks`] with `chunk_records` records per chunk (1 for records
/// that are themselves large, such as a glTF primitive).
///
/// # Errors
/// As [`write_chunks`].
pub(crate) fn write_chunks_of<T, W, F>(
    w: &mut W,
    records: &[T],
    chunk_records: usize,
    bytes_per_record: usize,
    encode: F,
) -> Result<(), ExportError>
where
    T: Sync,
    W: Write + Send + ?Sized,
    F: Fn(usize, &[T], &mut Vec<u8>) -> Result<(), ExportError> + Sync,
{
    let chunk = chunk_records.max(1);
    let batch = chunk * CHUNKS_PER_THREAD * rayon::current_num_threads().max(1);
    let encode_batch = |g: usize, bufs: &mut Vec<Vec<u8>>| -> Result<(), ExportError> {
        let group = &records[g * batch..records.len().min((g + 1) * batch)];
        let chunks = group.len().div_ceil(chunk);
        // Buffers are kept from batch to batch (no new pages to fault in).
        bufs.resize_with(chunks, Vec::new);
        let done: Vec<Result<(), ExportError>> = group
            .par_chunks(chunk)
            .zip(bufs.par_iter_mut())
            .enumerate()
            .map(|(c, (records, buf))| {
                buf.clear();
                buf.reserve(records.len() * bytes_per_record);
                encode(g * batch + c * chunk, records, buf)
            })
            .collect();
        done.into_iter().collect()
    };
    let write_batch = |w: &mut W, bufs: &[Vec<u8>]| -> Result<(), ExportError> {
        bufs.iter().try_for_each(|b| w.write_all(b))?;
        Ok(())
    };
    let batches = records.len().div_ceil(batch);
    let (mut ready, mut spare) = (Vec::new(), Vec::new());
    if batches > 0 {
        encode_batch(0, &mut ready)?;
    }
    for g in 1..batches {
        let (written, encoded) =
            rayon::join(|| write_batch(w, &ready), || encode_batch(g, &mut spare));
        written?;
        encoded?;
        std::mem::swap(&mut ready, &mut spare);
    }
    if batches > 0 {
        write_batch(w, &ready)?;
    }
    Ok(())
}

/// [`write_chunks`] for records of `N` bytes each: `encode(index, record,
/// bytes)` fills one record's bytes (`index` is its position in
/// `records`). A chunk's buffer is sized once and filled in place, which
/// the compiler turns into plain stores (no capacity check per value).
///
/// # Errors
/// [`ExportError::Io`] from `w`.
pub(crate) fn write_fixed<const N: usize, T, W, F>(
    w: &mut W,
    records: &[T],
    encode: F,
) -> Result<(), ExportError>
where
    T: Sync,
    W: Write + Send + ?Sized,
    F: Fn(usize, &T, &mut [u8; N]) + Sync,
{
    write_chunks(w, records, N, |first, chunk, buf| {
        let start = buf.len();
        buf.resize(start + N * chunk.len(), 0);
        let (out, _) = buf[start..].as_chunks_mut::<N>();
        for (k, (o, r)) in out.iter_mut().zip(chunk).enumerate() {
            encode(first + k, r, o);
        }
        Ok(())
    })
}

/// Writes the little-endian bytes of `v` into `out` (which holds `4·v.len()`
/// bytes).
#[inline]
pub(crate) fn put_f32s(out: &mut [u8], v: &[f32]) {
    for (o, x) in out.chunks_exact_mut(4).zip(v) {
        o.copy_from_slice(&x.to_le_bytes());
    }
}

/// Writes the little-endian bytes of `v` into `out` (which holds `4·v.len()`
/// bytes).
#[inline]
pub(crate) fn put_u32s(out: &mut [u8], v: &[u32]) {
    for (o, x) in out.chunks_exact_mut(4).zip(v) {
        o.copy_from_slice(&x.to_le_bytes());
    }
}

/// Runs `f` on a rayon worker thread, so that the writer's parallel sections
/// start from inside the pool: a section entered from outside hands its work
/// to the pool and waits to be woken, once per batch (tens of µs each, far
/// more on a loaded machine), where one entered from a worker costs well
/// under a microsecond.
pub(crate) fn on_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    if rayon::current_thread_index().is_some() {
        f()
    } else {
        rayon::scope(|_| f())
    }
}

#[cfg(test)]
mod test {
    #![allow(clippy::unwrap_used, reason = "tests")]
    use super::*;

    #[test]
    fn chunks_come_out_in_order() {
        let records: Vec<u32> = (0..1_000_000).collect();
        let mut out = Vec::new();
        write_chunks(&mut out, &records, 4, |first, c, buf| {
            assert_eq!(c[0] as usize, first);
            for r in c {
                buf.extend_from_slice(&r.to_le_bytes());
            }
            Ok(())
        })
        .unwrap();
        let want: Vec<u8> = records.iter().flat_map(|r| r.to_le_bytes()).collect();
        assert_eq!(out, want);
    }

    #[test]
    fn the_first_error_in_order_wins() {
        let records: Vec<u32> = (0..100_000).collect();
        let mut out = Vec::new();
        let r = write_chunks(&mut out, &records, 4, |_, c, _| match c[0] {
            x if x >= CHUNK_RECORDS as u32 => Err(ExportError::Json(format!("chunk at {x}"))),
            _ => Ok(()),
        });
        assert!(matches!(r, Err(ExportError::Json(m)) if m == format!("chunk at {CHUNK_RECORDS}")));
    }
}
