//! Fuzz target for the progressive stream decoder (`.cstream`): arbitrary bytes
//! through `cota_io::stream_file::decode_stream_bytes`, then the decoded mesh
//! and surface. Any result is fine; a panic, an abort or an out-of-memory is a
//! bug. Heads announcing grids above 2^20 samples are skipped (they are valid
//! but only cost memory). Seeds: `fuzz/corpus/stream_decode/`, written by the
//! ignored test `write_stream_fuzz_seeds` in crates/cota-io/tests/stream.rs.
#![no_main]

use cota_io::stream_file::{decode_stream_bytes, StreamLimit};
use libfuzzer_sys::fuzz_target;

/// Offset of the grid width in the file: magic 8, version 2, head length 4.
const WIDTH_AT: usize = 14;

fn samples(data: &[u8]) -> u64 {
    let at = |i: usize| {
        data.get(i..i + 4)
            .map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u64)
    };
    at(WIDTH_AT) * at(WIDTH_AT + 4)
}

fuzz_target!(|data: &[u8]| {
    if samples(data) > 1 << 20 {
        return;
    }
    if let Ok(d) = decode_stream_bytes(data, &StreamLimit::ALL) {
        let _ = d.decoder.mesh();
        let _ = d.decoder.heights_m();
    }
});
