//! The meshoptimizer vertex codec (mode `ATTRIBUTES`, bitstream version 0),
//! written from Appendix A of the `EXT_meshopt_compression` specification:
//!
//! * a header byte `0xa0`;
//! * attribute blocks of `min((8192 / stride) & !15, 256)` elements; in
//!   each, one data block per byte of the element: the zigzagged differences
//!   of that byte from the previous element's, in groups of 16, each group
//!   stored as zero (no bytes), 2-bit or 4-bit values with an all-ones
//!   sentinel for a byte that follows, or 16 plain bytes; two header bits
//!   per group say which (least significant first);
//! * a tail: the baseline element (the deltas of the very first element are
//!   from it), zero-padded in front to 32 bytes.
//!
//! Here the baseline is the first element, and each group takes the
//! smallest of the four encodings.

use super::MeshoptError;

/// Elements per attribute block for a stride.
fn block_elements(stride: usize) -> usize {
    ((8192 / stride) & !15).min(256)
}

/// The 8-bit zigzag code of a byte difference.
fn zigzag8(d: u8) -> u8 {
    if d & 0x80 != 0 {
        !(d << 1)
    } else {
        d << 1
    }
}

/// Bytes a group of 16 codes takes with sentinel values of `bits` (2 or 4).
fn sentinel_size(codes: &[u8; 16], bits: u32) -> usize {
    let sentinel = (1u8 << bits) - 1;
    let packed = 16 * bits as usize / 8;
    packed + codes.iter().filter(|&&c| c >= sentinel).count()
}

/// Appends a group in sentinel coding of `bits` (2 or 4): the packed values,
/// first element in the most significant bits, then the escaped bytes.
fn push_sentinel(out: &mut Vec<u8>, codes: &[u8; 16], bits: u32) {
    let sentinel = (1u8 << bits) - 1;
    let per_byte = 8 / bits as usize;
    for chunk in codes.chunks(per_byte) {
        let mut byte = 0u8;
        for (k, &c) in chunk.iter().enumerate() {
            let shift = 8 - bits as usize * (k + 1);
            byte |= c.min(sentinel) << shift;
        }
        out.push(byte);
    }
    out.extend(codes.iter().filter(|&&c| c >= sentinel));
}

/// Appends one data block: the header bits of its groups, then the groups.
fn push_data_block(out: &mut Vec<u8>, codes: &[u8]) {
    let groups: Vec<[u8; 16]> = codes
        .chunks(16)
        .map(|c| {
            let mut g = [0u8; 16];
            g[..c.len()].copy_from_slice(c);
            g
        })
        .collect();
    let modes: Vec<u8> = groups
        .iter()
        .map(|g| {
            if g.iter().all(|&c| c == 0) {
                return 0;
            }
            let sizes = [sentinel_size(g, 2), sentinel_size(g, 4), 16];
            let best = (0..3).min_by_key(|&k| sizes[k]).unwrap_or(2);
            best as u8 + 1
        })
        .collect();
    for four in modes.chunks(4) {
        let byte = four
            .iter()
            .enumerate()
            .fold(0u8, |b, (k, &m)| b | (m << (2 * k)));
        out.push(byte);
    }
    for (g, &mode) in groups.iter().zip(&modes) {
        match mode {
            0 => {}
            1 => push_sentinel(out, g, 2),
            2 => push_sentinel(out, g, 4),
            _ => out.extend_from_slice(g),
        }
    }
}

/// Encodes `data`, elements of `stride` bytes each, as a vertex buffer
/// stream (`EXT_meshopt_compression` mode `ATTRIBUTES`, filter `NONE`).
///
/// # Errors
/// [`MeshoptError`] when `stride` is not a multiple of 4 in 4..=256 or
/// `data` is not a whole number of elements.
pub fn encode_vertex_buffer(data: &[u8], stride: usize) -> Result<Vec<u8>, MeshoptError> {
    if stride == 0 || !stride.is_multiple_of(4) || stride > 256 {
        return Err(MeshoptError(format!(
            "vertex stride: expected a multiple of 4 up to 256, found {stride}"
        )));
    }
    if !data.len().is_multiple_of(stride) {
        return Err(MeshoptError(format!(
            "vertex data: {} bytes is not a whole number of {stride}-byte elements",
            data.len()
        )));
    }
    let count = data.len() / stride;
    let mut out = vec![0xa0];
    let baseline: Vec<u8> = data.get(..stride).map_or(vec![0; stride], <[u8]>::to_vec);
    let mut previous = baseline.clone();
    let per_block = block_elements(stride);
    for start in (0..count).step_by(per_block) {
        let n = per_block.min(count - start);
        let block = &data[start * stride..(start + n) * stride];
        for (k, prev) in previous.iter_mut().enumerate() {
            let mut last = *prev;
            let codes: Vec<u8> = block
                .chunks_exact(stride)
                .map(|e| {
                    let d = e[k].wrapping_sub(last);
                    last = e[k];
                    zigzag8(d)
                })
                .collect();
            *prev = last;
            push_data_block(&mut out, &codes);
        }
    }
    out.resize(out.len() + 32usize.saturating_sub(stride), 0);
    out.extend_from_slice(&baseline);
    Ok(out)
}
