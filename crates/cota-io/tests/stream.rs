//! The progressive stream on real data: lossless round trips, every prefix
//! checked crack-free within its stated error, truncation and corruption
//! reported without panics, and the fuzz seeds of `stream_decode` replayed.
#![allow(clippy::unwrap_used, clippy::panic, reason = "tests")]

mod common;

use common::workspace_root;
use cota_core::stream::{encode, StreamDecoder, StreamOptions};
use cota_core::voids::{fill_voids, FillOptions};
use cota_core::{check_mesh, Bitree, CheckOptions, ExtractOptions, GeoRef, HeightGrid};
use cota_io::stream_file::{
    crc32, decode_stream_bytes, step_end_offsets, stream_bytes, StreamFileError, StreamLimit,
    StreamReader,
};
use cota_io::{read_dem, ReadOptions};

/// The bundled SRTM tile, voids filled and rounded to whole metres (SRTM's
/// own lattice), so the default 1 m quantum is lossless.
fn s29() -> HeightGrid {
    let path = workspace_root().join("fixtures/S29W072.hgt.zip");
    let mut g = read_dem(&path, &ReadOptions::DEFAULT).unwrap().grid;
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    for h in g.heights_mut() {
        *h = h.round();
    }
    g
}

fn small(w: usize, h: usize) -> HeightGrid {
    let v = (0..w * h)
        .map(|i| (((i * 7919) % 23) as f32 + (i / w) as f32 * 3.0).round())
        .collect();
    HeightGrid::new(w, h, v, GeoRef::unreferenced(30.0)).unwrap()
}

#[test]
fn srtm_round_trip_every_prefix_checked() {
    let grid = s29();
    let s = encode(&grid, &StreamOptions::default()).unwrap();
    assert!(s.lattice_exact);
    let bytes = stream_bytes(&s, grid.georef());
    let ends = step_end_offsets(&s, grid.georef());
    assert_eq!(*ends.last().unwrap(), bytes.len() as u64);
    let tree = Bitree::build(&grid).unwrap();
    // Feed the bytes in odd-sized chunks, as they would arrive.
    let mut r = StreamReader::new();
    let mut k = 0;
    for chunk in bytes.chunks(61) {
        let frames = r.push(chunk).unwrap();
        assert!(frames.len() <= 1);
        for frame in frames {
            let d = r.decoder().unwrap();
            let mesh = d.mesh();
            let step = &s.steps[k];
            assert_eq!(frame.info.index, k);
            assert_eq!(frame.end_offset, ends[k]);
            assert_eq!(frame.info.max_error_m, step.max_error_m);
            let want = tree
                .extract(&ExtractOptions::max_error_m(step.threshold_m))
                .unwrap()
                .mesh;
            assert_eq!(mesh, want, "step {k}");
            check_mesh(
                &grid,
                &mesh,
                &CheckOptions::conforming(frame.info.max_error_m),
            )
            .unwrap_or_else(|e| panic!("step {k}: {e}"));
            k += 1;
        }
    }
    r.finish().unwrap();
    assert_eq!(k, s.steps.len());
    let d = r.decoder().unwrap();
    assert_eq!(d.max_error_m(), Some(0.0));
    // Lossless: every vertex carries its sample's exact height, and the whole
    // surface decodes to the source grid.
    let mesh = d.mesh();
    for v in &mesh.vertices {
        assert_eq!(v.z_m, grid.get(v.col as usize, v.row as usize));
    }
    assert_eq!(
        mesh,
        tree.extract(&ExtractOptions::max_error_m(0.0))
            .unwrap()
            .mesh
    );
    assert_eq!(d.heights_m().unwrap(), grid.heights());
    assert_eq!(r.georef(), Some(grid.georef()));
    // The target: at most 1 byte per triangle of the mesh it decodes to.
    let per_tri = bytes.len() as f64 / mesh.triangle_count() as f64;
    assert!(per_tri <= 1.0, "{per_tri} bytes per triangle");
}

#[test]
fn srtm_fictitious_marks_round_trip() {
    use cota_core::refine::{refine_marks, Mode, RefineOptions};
    use cota_core::stream::encode_marks;
    let grid = s29();
    for (mode, e) in [
        (Mode::Fictitious { watertight: true }, 5.0),
        (Mode::Fictitious { watertight: false }, 10.0),
        (Mode::Conforming, 2.0),
    ] {
        let crit = cota_core::MaxVerticalError { max_error_m: e };
        let (r, marks) =
            refine_marks(&grid, &crit, &RefineOptions::DEFAULT.with_mode(mode)).unwrap();
        let s = encode_marks(&grid, &marks, mode, e, &StreamOptions::default()).unwrap();
        let bytes = stream_bytes(&s, grid.georef());
        let d = decode_stream_bytes(&bytes, &StreamLimit::ALL).unwrap();
        let mesh = d.decoder.mesh();
        assert_eq!(mesh, r.mesh, "{mode:?}");
        let check = CheckOptions::conforming(e)
            .with_conforming(mode.is_conforming())
            .with_allow_fictitious(true);
        check_mesh(&grid, &mesh, &check).unwrap();
        // Fictitious points are never sent: fewer heights than vertices.
        assert!(s.steps[0].new_points <= r.transmitted_points);
        assert!(bytes.len() as f64 / (mesh.triangle_count() as f64) < 1.0);
    }
}

#[test]
fn float_data_on_a_decimetre_lattice_is_lossless() {
    let w = 45;
    let v: Vec<f32> = (0..w * 31)
        .map(|i| (((i * 7919) % 1000) as f64 * 0.1 + 1200.0) as f32)
        .collect();
    let grid = HeightGrid::new(w, 31, v, GeoRef::unreferenced(10.0)).unwrap();
    let s = encode(&grid, &StreamOptions::default().with_quantum_m(0.1)).unwrap();
    assert!(s.lattice_exact);
    let d = decode_stream_bytes(&stream_bytes(&s, grid.georef()), &StreamLimit::ALL).unwrap();
    assert_eq!(d.decoder.heights_m().unwrap(), grid.heights());
    let mesh = d.decoder.mesh();
    check_mesh(&grid, &mesh, &CheckOptions::conforming(0.0)).unwrap();
}

#[test]
fn limits_pick_prefixes() {
    let grid = small(65, 40);
    let s = encode(&grid, &StreamOptions::default()).unwrap();
    let bytes = stream_bytes(&s, grid.georef());
    let ends = step_end_offsets(&s, grid.georef());
    assert!(ends.len() >= 3);
    let d =
        decode_stream_bytes(&bytes, &StreamLimit::ALL.with_max_bytes(Some(ends[1] + 3))).unwrap();
    assert_eq!(d.steps.len(), 2);
    let e = s.steps[2].max_error_m;
    let d = decode_stream_bytes(&bytes, &StreamLimit::ALL.with_max_error_m(Some(e))).unwrap();
    assert_eq!(d.decoder.max_error_m(), Some(e));
    check_mesh(&grid, &d.decoder.mesh(), &CheckOptions::conforming(e)).unwrap();
    let err = decode_stream_bytes(&bytes, &StreamLimit::ALL.with_max_bytes(Some(10))).unwrap_err();
    assert!(matches!(err, StreamFileError::Truncated { .. }), "{err}");
}

#[test]
fn truncated_streams_are_reported() {
    let grid = small(33, 17);
    let s = encode(&grid, &StreamOptions::default()).unwrap();
    let bytes = stream_bytes(&s, grid.georef());
    let ends = step_end_offsets(&s, grid.georef());
    for n in 0..bytes.len() {
        let r = decode_stream_bytes(&bytes[..n], &StreamLimit::ALL);
        match r {
            Err(StreamFileError::Truncated {
                expected, found, ..
            }) => assert!(expected > found, "{n}: {expected} {found}"),
            Err(e) => panic!("{n}: unexpected {e}"),
            Ok(_) => panic!("{n}: a truncated stream decoded"),
        }
        // Incrementally, the complete steps of a prefix are still usable.
        let mut rd = StreamReader::new();
        let got = rd.push(&bytes[..n]).unwrap().len();
        assert_eq!(got, ends.iter().filter(|&&e| e <= n as u64).count());
    }
    let msg = decode_stream_bytes(&bytes[..bytes.len() - 1], &StreamLimit::ALL)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("expected") && msg.contains("found"), "{msg}");
}

#[test]
fn corrupted_streams_are_reported_never_panic() {
    let grid = small(33, 17);
    let s = encode(&grid, &StreamOptions::default()).unwrap();
    let bytes = stream_bytes(&s, grid.georef());
    // Flipped bytes: the checksums catch them.
    for i in 0..bytes.len() {
        let mut b = bytes.clone();
        b[i] ^= 0x5A;
        assert!(
            decode_stream_bytes(&b, &StreamLimit::ALL).is_err(),
            "byte {i}"
        );
    }
    let mut b = bytes.clone();
    b[0] = b'X';
    let e = decode_stream_bytes(&b, &StreamLimit::ALL).unwrap_err();
    assert!(matches!(e, StreamFileError::BadMagic { .. }), "{e}");
    // Corrupted payloads with matching checksums reach the core decoder: it
    // may fail or decode garbage, but never panics, and a failed step leaves
    // the previous prefix intact.
    let header = s.header.clone();
    for i in 0..s.steps[1].payload.len() {
        for x in [0x01u8, 0x80, 0xFF] {
            let mut d = StreamDecoder::new(header.clone());
            d.apply_step(&s.steps[0].payload).unwrap();
            let before = d.mesh();
            let mut p = s.steps[1].payload.clone();
            p[i] ^= x;
            if d.apply_step(&p).is_err() {
                assert_eq!(d.mesh(), before);
                assert_eq!(d.steps().len(), 1);
            }
            let _ = d.heights_m();
        }
    }
    let _ = crc32(&bytes);
}

/// Replays the seeds of the `stream_decode` fuzz target like the target does.
#[test]
fn stream_fuzz_seeds_replay() {
    let dir = workspace_root().join("fuzz/corpus/stream_decode");
    let mut n = 0;
    let mut valid = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        let bytes = std::fs::read(&p).unwrap();
        let r = decode_stream_bytes(&bytes, &StreamLimit::ALL);
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if name.starts_with("seed-valid") {
            let d = r.unwrap_or_else(|e| panic!("{name}: {e}"));
            let mesh = d.decoder.mesh();
            assert!(mesh.triangle_count() >= 2, "{name}");
            valid += 1;
        } else if let Ok(d) = r {
            let _ = (d.decoder.mesh(), d.decoder.heights_m());
        }
        n += 1;
    }
    assert!(n >= 6 && valid >= 3, "{n} seeds, {valid} valid");
}

/// Writes the seed corpus of `stream_decode` (run with `--ignored` to refresh).
#[test]
#[ignore = "writes fuzz/corpus/stream_decode"]
fn write_stream_fuzz_seeds() {
    let dir = workspace_root().join("fuzz/corpus/stream_decode");
    std::fs::create_dir_all(&dir).unwrap();
    let put = |name: &str, b: &[u8]| std::fs::write(dir.join(name), b).unwrap();
    let g = small(9, 9);
    let s = encode(&g, &StreamOptions::default()).unwrap();
    let b = stream_bytes(&s, g.georef());
    let steps: usize = s.steps.iter().map(|x| x.payload.len() + 8).sum();
    put("seed-valid-9x9.cstream", &b);
    {
        use cota_core::refine::{refine_marks, Mode, RefineOptions};
        let g = small(13, 11);
        let mode = Mode::Fictitious { watertight: false };
        let crit = cota_core::MaxVerticalError { max_error_m: 4.0 };
        let (_, marks) = refine_marks(&g, &crit, &RefineOptions::DEFAULT.with_mode(mode)).unwrap();
        let s = cota_core::stream::encode_marks(&g, &marks, mode, 4.0, &StreamOptions::default())
            .unwrap();
        put(
            "seed-valid-faithful-13x11.cstream",
            &stream_bytes(&s, g.georef()),
        );
    }
    let g = small(17, 6);
    let s = encode(&g, &StreamOptions::default().with_quantum_m(0.5)).unwrap();
    let b2 = stream_bytes(&s, g.georef());
    put("seed-valid-17x6.cstream", &b2);
    put("seed-truncated.cstream", &b2[..b2.len() / 2]);
    let mut c = b.clone();
    let last = c.len() - 3;
    c[last] ^= 0x10;
    put("seed-bad-crc.cstream", &c);
    put("seed-head-only.cstream", &b[..b.len() - steps]);
}
