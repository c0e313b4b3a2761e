//! Progressive transmission: a compact coarse-to-fine stream of the bitree's
//! split points that never sends a coordinate.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §3 ("Transmisión progresiva"): send the
//! coarse mesh `N0`, then, for successively finer tolerances, the points each
//! one adds; the receiver rebuilds the hierarchy itself. Here every position is
//! implicit in the hierarchy ([`crate::hierarchy`]) and only split decisions
//! and height residuals travel, entropy-coded ([`coder`]).
//!
//! # Overview
//! 1. **Quantise.** Heights become integers `q = round(h / quantum_m)`; the
//!    sender meshes the quantised grid (`q · quantum_m` as `f32`), so every
//!    stated error is exact for it. When every source height already sits on the
//!    lattice (integer metres for SRTM with the default quantum of 1 m; 0.1 m
//!    data with `quantum_m = 0.1`: exactly when `(q · quantum_m) as f32 == h`,
//!    reported as [`EncodedStream::lattice_exact`]) the stream is lossless;
//!    otherwise add `quantum_m / 2` to the stated errors for the source grid.
//! 2. **Steps.** Thresholds `E_0 = f32::MAX > E_1 > … > E_last`: powers of two
//!    from the largest finite error down to `quantum_m`, then the requested
//!    `max_error_m` (default 0). Because [`crate::Bitree`]'s error map is monotone and
//!    diamond-shared, the split set `{m : err[m] > E_k}` is closed under the
//!    hierarchy's dependencies, so after step `k` the receiver holds exactly the
//!    mesh of `Bitree::extract(E_k)`. Step 0 is paper 000's `N0`: the coarsest
//!    mesh the grid's border allows.
//! 3. **Walk.** Each step walks the tree from the two roots exactly as
//!    extraction does (children in [`crate::hierarchy::Tri::children`] order). Straddling
//!    triangles split without a bit. At an inside triangle whose split point is
//!    not yet split and not yet decided in this step, one bit says whether it
//!    splits now. When it splits and its split point has no height yet, the
//!    height follows as a residual against the prediction
//!    `floor((q[a] + q[b]) / 2)` (the midpoint of the hypotenuse `a`–`b`; when
//!    an end lies outside the grid, the floor of the mean of the triangle's
//!    known vertices, else 0). Both triangles of a diamond read the one
//!    decision, so the receiver's mesh is crack-free after every step.
//! 4. **Contexts.** Split bits use an adaptive probability per (level, step,
//!    whether the triangle was created in this step); residuals one
//!    [`coder::ResidualModel`] per (level, step). Level `= 2·log2(s) + [A]` for a
//!    triangle on an `s`-square (`A`: the square's halves, `B`: their
//!    children). Steps above 15 share the context of step 15. Models persist
//!    across steps, and each step is its own range-coded block, so a receiver
//!    can stop after any step.
//! 5. **Stated error.** Each step states `E_k`, the largest `err[m]` among the
//!    split points it left unsplit (0 when none): an upper bound of the true
//!    error of that prefix's mesh at every sample, at most the threshold.
//!
//! # Bit layout
//! Header ([`StreamHeader::to_bytes`], 52 bytes, little-endian): `width: u32`,
//! `height: u32`, `quantum_m: f64`, then `q` of the padded square's corners
//! `(0,0), (N,0), (0,N), (N,N)` as four `i64` (0 for corners outside the grid),
//! then `kind: u32` ([`StreamKind`]: 0 error steps, this file; 1–3 a refined
//! mesh's marks in conforming, fictitious or faithful mode,
//! `marks`).
//!
//! Step payload: `max_error_m: f32` (little-endian, the stated `E_k`), then one
//! range-coded block ([`coder::RangeEncoder`]) holding, in walk order, for each
//! candidate triangle `split: bit` and, for each new point,
//! `residual` as binarised by [`coder::ResidualModel`]. Framing (magic, lengths,
//! checksums, georeference) is `cota-io`'s business.
//!
//! # Decoding
//! [`StreamDecoder`] applies steps one by one; a step that fails to decode
//! (truncated, corrupted) is rolled back, so the decoder always holds the last
//! good prefix. Its [`StreamDecoder::mesh`] equals `Bitree::extract(E_k)` of the
//! quantised grid, vertex for vertex.
//!
//! Meshes of other criteria and of the fictitious modes (`refine`'s `Marks`,
//! where fictitious points cost a flag and no height) are streamed coarse to
//! fine by [`encode_marks_progressive`] (vertical-error tolerances) or
//! [`encode_marks_steps`] (any nested marks), `marks`, and
//! decoded step by step by the same [`StreamDecoder`]; their stated errors
//! are measured exactly and need not decrease from step to step.

pub mod coder;
mod decoder;
mod format;
mod marks;
mod models;
mod state;
mod steps;

pub use decoder::{StepInfo, StreamDecoder};
pub use format::{
    quantize, EncodedStep, EncodedStream, StreamError, StreamHeader, StreamKind, StreamOptions,
    HEADER_BYTES,
};
pub use marks::{
    encode_marks, encode_marks_progressive, encode_marks_progressive_with_progress,
    encode_marks_steps,
};
pub use steps::{encode, encode_with_progress};

#[cfg(test)]
#[allow(clippy::unwrap_used, reason = "tests")]
mod test {
    use super::*;
    use crate::grid::GeoRef;
    use crate::{check_mesh, Bitree, CheckOptions, ExtractOptions, HeightGrid, Mesh};

    fn grid(w: usize, h: usize) -> HeightGrid {
        let v = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                (200.0 + 40.0 * (x * 0.21).sin() * (y * 0.17).cos()).round()
                    + ((i * 7919) % 5) as f32
            })
            .collect();
        HeightGrid::new(w, h, v, GeoRef::unreferenced(30.0)).unwrap()
    }

    #[test]
    fn every_prefix_is_extract_and_checks() {
        for (w, h) in [(33, 33), (37, 23), (2, 9), (40, 41)] {
            let g = grid(w, h);
            let s = encode(&g, &StreamOptions::default()).unwrap();
            assert!(s.lattice_exact);
            let tree = Bitree::build(&g).unwrap();
            let hb = StreamHeader::from_bytes(&s.header.to_bytes()).unwrap();
            let mut d = StreamDecoder::new(hb);
            for step in &s.steps {
                let info = d.apply_step(&step.payload).unwrap();
                let mesh = d.mesh();
                let want = tree
                    .extract(&ExtractOptions::max_error_m(step.threshold_m))
                    .unwrap()
                    .mesh;
                assert_eq!(mesh, want, "{w}x{h} step {}", info.index);
                assert_eq!(mesh.triangle_count(), step.triangles);
                check_mesh(&g, &mesh, &CheckOptions::conforming(info.max_error_m)).unwrap();
            }
            let z = d.heights_m().unwrap_or_default();
            assert_eq!(z, g.heights());
        }
    }

    #[test]
    fn random_payloads_never_panic() {
        let g = grid(21, 13);
        let s = encode(&g, &StreamOptions::default()).unwrap();
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        for len in 0..400usize {
            let mut d = StreamDecoder::new(s.header.clone());
            let mut p = vec![0u8; 4];
            for _ in 0..len {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                p.push(x as u8);
            }
            if d.apply_step(&p).is_ok() {
                let _ = d.apply_step(&p);
                let m = d.mesh();
                assert!(m.triangle_count() >= 2);
                let _ = d.heights_m();
            } else {
                assert!(d.steps().is_empty());
                assert_eq!(d.mesh(), Mesh::default());
            }
        }
    }

    #[test]
    fn bad_options_and_headers_are_errors() {
        let g = grid(9, 9);
        let o = StreamOptions::default().with_quantum_m(0.0);
        assert!(matches!(encode(&g, &o), Err(StreamError::BadQuantum(_))));
        let o = StreamOptions::default().with_max_error_m(-1.0);
        assert!(matches!(encode(&g, &o), Err(StreamError::BadMaxError(_))));
        let mut h = encode(&g, &StreamOptions::default())
            .unwrap()
            .header
            .to_bytes();
        assert!(StreamHeader::from_bytes(&h[..47]).is_err());
        h[0] = 1;
        let e = StreamHeader::from_bytes(&h).unwrap_err().to_string();
        assert!(e.contains("expected") && e.contains("found 1x9"), "{e}");
    }
}
