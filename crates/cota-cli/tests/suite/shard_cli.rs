//! Sharded `cota tiles` (issue 20): `--plan`, `--shard I/N` and `--reduce`
//! give a directory byte-identical to one plain `cota tiles` run, for 1, 2
//! and 3 shards, on the bundled sample and on the two-tile mosaic; a shard
//! run again is idempotent; a reduce with a shard missing is refused, and
//! the reduce removes the temporary files a killed shard left.
#![allow(clippy::unwrap_used, clippy::panic)]

use crate::common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use common::{cota, stderr, stdout};

/// Every file under `dir` (hidden ones included), by relative path.
fn files(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(dir).unwrap().to_path_buf();
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    out
}

fn run_ok(args: &[&str]) -> String {
    let r = cota(args);
    assert!(r.status.success(), "{args:?}: {}", stderr(&r));
    stdout(&r)
}

/// Plain run, then 1, 2, 3 and 5 shards + reduce, each compared file by file.
fn sharded_equals_plain(inputs: &[&str], settings: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain");
    let mut args: Vec<&str> = vec!["tiles"];
    args.extend(inputs);
    args.extend(settings);
    let p = plain.to_str().unwrap();
    run_ok(&[&args[..], &["-o", p]].concat());
    let want = files(&plain);
    assert!(want.len() > 5, "{want:?}");
    for n in [1, 2, 3, 5u32] {
        let out = dir.path().join(format!("sharded{n}"));
        let o = out.to_str().unwrap();
        let ns = n.to_string();
        let plan = run_ok(&[&args[..], &["-o", o, "--plan", "--shards", &ns, "--json"]].concat());
        let plan: serde_json::Value = serde_json::from_str(&plan).unwrap();
        let planned: u64 = plan["plan"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s["tiles"].as_u64().unwrap())
            .sum();
        // The reduce cuts the tiles above the band zoom; the shards list the
        // others once: as many as the pyramid has (but layer.json and the
        // run manifest).
        let coarse = plan["coarse_tiles"].as_u64().unwrap();
        assert!(coarse > 0, "{plan}");
        assert_eq!((planned + coarse) as usize, want.len() - 2, "{plan}");
        let terrain = |d: &Path| {
            let f = files(d);
            f.keys()
                .filter(|k| k.extension().is_some_and(|e| e == "terrain"))
                .count()
        };
        assert_eq!(terrain(&out), 0, "the plan step writes no tile");
        for i in (0..n).rev() {
            let s = format!("{i}/{n}");
            run_ok(&[&args[..], &["-o", o, "--shard", &s]].concat());
        }
        assert!(
            !out.join("layer.json").exists(),
            "the shards leave layer.json to the reduce"
        );
        assert_eq!(
            terrain(&out) as u64,
            planned,
            "the shards write only their tiles"
        );
        let r = run_ok(&["tiles", "-o", o, "--reduce", "--shards", &ns, "--json"]);
        let r: serde_json::Value = serde_json::from_str(&r).unwrap();
        // The reduce counts the whole pyramid, and cut the coarse tiles from
        // the shards' partial maxima.
        assert_eq!(r["tiles"].as_u64(), Some(want.len() as u64 - 2), "{r}");
        assert_eq!(r["coarse_written"].as_u64(), Some(coarse), "{r}");
        assert!(files(&out) == want, "{n} shards differ from the plain run");
    }
}

#[test]
fn shards_and_reduce_equal_plain_run_on_the_sample() {
    sharded_equals_plain(&[], &["--max-zoom", "8", "--normals", "--metadata"]);
}

#[test]
fn shards_and_reduce_equal_plain_run_on_the_two_tile_mosaic() {
    let (Some(a), Some(b)) = (
        common::shared("srtm/N00E010.hgt"),
        common::shared("srtm/N00E011.hgt.zip"),
    ) else {
        return;
    };
    let (a, b) = (
        a.to_str().unwrap().to_owned(),
        b.to_str().unwrap().to_owned(),
    );
    sharded_equals_plain(
        &[&a, &b],
        &["--max-zoom", "7", "--gzip", "--normals", "--watermask"],
    );
}

#[test]
fn shard_is_idempotent_and_reduce_needs_every_shard() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    let o = out.to_str().unwrap();
    let base = ["tiles", "--max-zoom", "7", "-o", o];
    let first = run_ok(&[&base[..], &["--shard", "1/2", "--json"]].concat());
    let first: serde_json::Value = serde_json::from_str(&first).unwrap();
    let written = first["written"].as_u64().unwrap();
    assert!(written > 0, "{first}");
    let before = files(&out);
    let again = run_ok(&[&base[..], &["--shard", "1/2", "--json"]].concat());
    let again: serde_json::Value = serde_json::from_str(&again).unwrap();
    assert_eq!(
        (again["written"].as_u64(), again["skipped"].as_u64()),
        (Some(0), Some(written))
    );
    assert!(
        files(&out) == before,
        "a shard run again changed the directory"
    );
    let r = cota(&["tiles", "-o", o, "--reduce", "--shards", "2"]);
    assert!(!r.status.success());
    assert!(stderr(&r).contains("missing shard(s) 0"), "{}", stderr(&r));
    assert!(!out.join("layer.json").exists());
    let bad = cota(&[&base[..], &["--shard", "2/2"]].concat());
    assert!(!bad.status.success());
    assert!(stderr(&bad).contains("expected I/N"), "{}", stderr(&bad));
}

/// The two-tile mosaic copied into a temporary directory (so a test can
/// move a file away): the directory, the western and the eastern file;
/// `None` without the shared data.
fn copied_pair() -> Option<(tempfile::TempDir, PathBuf, PathBuf)> {
    let a = common::shared("srtm/N00E010.hgt")?;
    let b = common::shared("srtm/N00E011.hgt.zip")?;
    let dir = tempfile::tempdir().unwrap();
    let (wa, eb) = (
        dir.path().join("N00E010.hgt"),
        dir.path().join("N00E011.hgt.zip"),
    );
    std::fs::copy(&a, &wa).unwrap();
    std::fs::copy(&b, &eb).unwrap();
    Some((dir, wa, eb))
}

/// The real pair relabelled across the antimeridian (N00E010 as N00E179,
/// N00E011 as N00W180: their shared column at ±180°) in a temporary
/// directory: the directory, the eastern-hemisphere and the
/// western-hemisphere file; `None` without the shared data.
fn pair_across_the_antimeridian() -> Option<(tempfile::TempDir, PathBuf, PathBuf)> {
    let a = common::shared("srtm/N00E010.hgt")?;
    let b = common::shared("srtm/N00E011.hgt.zip")?;
    let dir = tempfile::tempdir().unwrap();
    let (e179, w180) = (
        dir.path().join("N00E179.hgt"),
        dir.path().join("N00W180.hgt.zip"),
    );
    std::fs::copy(&a, &e179).unwrap();
    std::fs::copy(&b, &w180).unwrap();
    Some((dir, e179, w180))
}

/// Across the antimeridian (the lattice counted from 0°, tiles addressed
/// modulo the world): the plan step (in parts, the files read alone), the
/// shards over parts and the reduce, and shards without a plan step, each
/// give the plain run's directory byte for byte; the easternmost of 4
/// shards over parts reads the W180 file alone.
#[test]
fn shards_equal_plain_run_across_the_antimeridian() {
    let Some((dir, e179, w180)) = pair_across_the_antimeridian() else {
        return;
    };
    let (east, west) = (e179.to_str().unwrap(), w180.to_str().unwrap());
    // (No --normals: their reach would make every shard read both files.)
    let base = [
        "tiles",
        east,
        west,
        "--max-zoom",
        "9",
        "--watermask",
        "--metadata",
    ];
    let plain = dir.path().join("plain");
    run_ok(&[&base[..], &["-o", plain.to_str().unwrap()]].concat());
    let want = files(&plain);
    let layer: serde_json::Value = serde_json::from_slice(&want[Path::new("layer.json")]).unwrap();
    assert_eq!(
        layer["bounds"],
        serde_json::json!([179.0, 0.0, -179.0, 1.0])
    );
    assert!(
        want.keys().any(|k| k.starts_with("9/0")),
        "no tile east of 180°"
    );
    let out = dir.path().join("parts");
    let o = out.to_str().unwrap();
    let plan = run_ok(&[&base[..], &["-o", o, "--plan", "--shards", "4", "--json"]].concat());
    // The plan's ranges are addresses: shard 1 ends at 180°, shard 2
    // starts there (Cesium's column 0).
    let plan: serde_json::Value = serde_json::from_str(&plan).unwrap();
    let x = |i: usize, k: &str| plan["plan"][i]["ranges"][0][k].as_u64();
    assert_eq!((x(1, "x1"), x(2, "x0")), (Some(1023), Some(0)), "{plan}");
    let frame = std::fs::read_to_string(out.join(".cota-shards-4.json")).unwrap();
    assert!(frame.contains("\"from_greenwich\":true"), "{frame}");
    let mut read = Vec::new();
    for i in 0..4 {
        let r = run_ok(
            &[
                &base[..],
                &["-o", o, "--shard", &format!("{i}/4"), "--json"],
            ]
            .concat(),
        );
        let r: serde_json::Value = serde_json::from_str(&r).unwrap();
        read.push(r["part"]["files_read"].clone());
    }
    assert_eq!(read[3], serde_json::json!([west]), "{read:?}");
    run_ok(&["tiles", "-o", o, "--reduce", "--shards", "4"]);
    assert!(
        files(&out) == want,
        "4 shards over parts differ from the plain run"
    );
    let out = dir.path().join("whole");
    let o = out.to_str().unwrap();
    for i in 0..2 {
        run_ok(&[&base[..], &["-o", o, "--shard", &format!("{i}/2")]].concat());
    }
    run_ok(&["tiles", "-o", o, "--reduce", "--shards", "2"]);
    assert!(
        files(&out) == want,
        "2 shards without a plan step differ from the plain run"
    );
}

/// After the plan step, a shard reads only the files its part of the
/// lattice needs: with N=4 on the two-tile mosaic the westmost shard runs
/// with the eastern tile gone, holds a lattice part narrower than the
/// window, and the pyramid after the other shards and the reduce is still
/// byte-identical to the plain run.
#[test]
fn shard_reads_only_the_files_of_its_part() {
    let Some((dir, wa, eb)) = copied_pair() else {
        return;
    };
    let (west, east) = (wa.to_str().unwrap(), eb.to_str().unwrap());
    let plain = dir.path().join("plain");
    let out = dir.path().join("sharded");
    let (p, o) = (plain.to_str().unwrap(), out.to_str().unwrap());
    let base = ["tiles", west, east, "--max-zoom", "10"];
    let whole = run_ok(&[&base[..], &["-o", p, "--json"]].concat());
    let whole: serde_json::Value = serde_json::from_str(&whole).unwrap();
    run_ok(&[&base[..], &["-o", o, "--plan", "--shards", "4"]].concat());
    let hidden = dir.path().join("elsewhere.zip");
    std::fs::rename(&eb, &hidden).unwrap();
    let first = run_ok(&[&base[..], &["-o", o, "--shard", "0/4", "--json"]].concat());
    let first: serde_json::Value = serde_json::from_str(&first).unwrap();
    assert_eq!(
        first["part"]["files_read"],
        serde_json::json!([west]),
        "{first}"
    );
    let (part_w, whole_w) = (
        first["lattice"]["window"][0].as_u64().unwrap(),
        whole["lattice"]["window"][0].as_u64().unwrap(),
    );
    assert!(part_w * 2 < whole_w, "part {part_w} of {whole_w} columns");
    // The eastern shard needs the eastern tile: a clear error without it.
    let r = cota(&[&base[..], &["-o", o, "--shard", "3/4"]].concat());
    assert!(!r.status.success());
    assert!(stderr(&r).contains("N00E011"), "{}", stderr(&r));
    std::fs::rename(&hidden, &eb).unwrap();
    for i in 1..4 {
        run_ok(&[&base[..], &["-o", o, "--shard", &format!("{i}/4")]].concat());
    }
    run_ok(&["tiles", "-o", o, "--reduce", "--shards", "4"]);
    assert!(
        files(&out) == files(&plain),
        "4 shards over parts differ from the plain run"
    );
}

/// A shard refuses a plan step's frame of other settings, or a damaged
/// one, naming it; it never panics.
#[test]
fn shard_refuses_a_frame_of_other_settings_or_a_damaged_one() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    let o = out.to_str().unwrap();
    run_ok(&[
        "tiles",
        "--max-zoom",
        "7",
        "-o",
        o,
        "--plan",
        "--shards",
        "2",
    ]);
    let r = cota(&["tiles", "--max-zoom", "8", "-o", o, "--shard", "0/2"]);
    assert!(!r.status.success());
    assert!(stderr(&r).contains("other settings"), "{}", stderr(&r));
    let frame = out.join(".cota-shards-2.json");
    let text = std::fs::read_to_string(&frame).unwrap();
    for bad in [
        "{}".to_owned(),
        "not json".to_owned(),
        text.replace("\"tile_cells\":64", "\"tile_cells\":63"),
        text.replace("\"source_size\":[1201,1201]", "\"source_size\":[0,0]"),
    ] {
        std::fs::write(&frame, &bad).unwrap();
        let r = cota(&["tiles", "--max-zoom", "7", "-o", o, "--shard", "0/2"]);
        assert_eq!(r.status.code(), Some(1), "{bad}: {}", stderr(&r));
        assert!(stderr(&r).contains(".cota-shards-2.json"), "{}", stderr(&r));
    }
}

/// The reduce refuses a missing, truncated or foreign partial file, and a
/// shard damaged band corners, naming the file; the directory stays as it
/// was, and the reduce succeeds once the file is back.
#[test]
fn reduce_refuses_a_missing_or_damaged_partial_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    let o = out.to_str().unwrap();
    let base = ["tiles", "--max-zoom", "7", "--normals", "-o", o];
    run_ok(&[&base[..], &["--plan", "--shards", "2"]].concat());
    for i in 0..2 {
        run_ok(&[&base[..], &["--shard", &format!("{i}/2")]].concat());
    }
    let partial = out.join(".cota-partial-1-of-2.bin");
    let good = std::fs::read(&partial).unwrap();
    let mut foreign = good.clone();
    foreign[8..].reverse();
    for bad in [
        good[..good.len() / 2].to_vec(),
        b"COTAPRT1".to_vec(),
        b"not a partial".to_vec(),
        foreign,
        Vec::new(),
    ] {
        std::fs::write(&partial, &bad).unwrap();
        let r = cota(&["tiles", "-o", o, "--reduce", "--shards", "2"]);
        assert_eq!(r.status.code(), Some(1), "{}", stderr(&r));
        assert!(
            stderr(&r).contains(".cota-partial-1-of-2.bin"),
            "{}",
            stderr(&r)
        );
        assert!(!out.join("layer.json").exists());
    }
    std::fs::remove_file(&partial).unwrap();
    let r = cota(&["tiles", "-o", o, "--reduce", "--shards", "2"]);
    assert_eq!(r.status.code(), Some(1), "{}", stderr(&r));
    assert!(
        stderr(&r).contains(".cota-partial-1-of-2.bin"),
        "{}",
        stderr(&r)
    );
    // Damaged corners: a shard (run again) names them.
    let corners = out.join(".cota-shards-2.corners");
    let kept = std::fs::read(&corners).unwrap();
    std::fs::write(&corners, &kept[..kept.len() - 3]).unwrap();
    let r = cota(&[&base[..], &["--shard", "1/2"]].concat());
    assert_eq!(r.status.code(), Some(1), "{}", stderr(&r));
    assert!(
        stderr(&r).contains(".cota-shards-2.corners"),
        "{}",
        stderr(&r)
    );
    std::fs::write(&corners, &kept).unwrap();
    run_ok(&[&base[..], &["--shard", "1/2"]].concat());
    run_ok(&["tiles", "-o", o, "--reduce", "--shards", "2"]);
    let left: Vec<_> = files(&out)
        .into_keys()
        .filter(|k| k.to_string_lossy().starts_with(".cota-") && !k.ends_with(".cota-tiles.json"))
        .collect();
    assert!(left.is_empty(), "the reduce leaves {left:?}");
}

/// The plan step in parts (`--plan --layout`, `--plan --part I` as
/// separate processes, then `--plan` merging them): the westmost plan part
/// runs with the eastern tile gone, a part run again is skipped, and the
/// pyramid after the shards and the reduce is byte-identical to the plain
/// run; the layout and part files are gone after the merge. A single file
/// has no parts: `--part` says the plan step reads the whole input.
#[test]
fn plan_step_in_parts_equals_plain_run() {
    let Some((dir, wa, eb)) = copied_pair() else {
        return;
    };
    let (west, east) = (wa.to_str().unwrap(), eb.to_str().unwrap());
    let plain = dir.path().join("plain");
    let out = dir.path().join("sharded");
    let (p, o) = (plain.to_str().unwrap(), out.to_str().unwrap());
    let base = ["tiles", west, east, "--max-zoom", "9", "--normals"];
    run_ok(&[&base[..], &["-o", p]].concat());
    let plan = [&base[..], &["-o", o, "--plan", "--shards", "3"]].concat();
    let layout = run_ok(&[&plan[..], &["--layout", "--json"]].concat());
    assert!(layout.contains(".cota-layout-3.json"), "{layout}");
    let hidden = dir.path().join("elsewhere.zip");
    std::fs::rename(&eb, &hidden).unwrap();
    let first = run_ok(&[&plan[..], &["--part", "0", "--json"]].concat());
    let first: serde_json::Value = serde_json::from_str(&first).unwrap();
    assert_eq!(first["files_read"], serde_json::json!([west]), "{first}");
    std::fs::rename(&hidden, &eb).unwrap();
    for i in ["2", "1", "0"] {
        let r = run_ok(&[&plan[..], &["--part", i, "--json"]].concat());
        let r: serde_json::Value = serde_json::from_str(&r).unwrap();
        assert_eq!(r["skipped"].as_bool(), Some(i == "0"), "{r}");
    }
    assert!(out.join(".cota-plan-2-of-3.bin").is_file());
    run_ok(&plan);
    for f in [".cota-layout-3.json", ".cota-plan-0-of-3.bin"] {
        assert!(!out.join(f).exists(), "{f} left after the plan step");
    }
    let done = run_ok(&[&plan[..], &["--part", "1"]].concat());
    assert!(done.contains("already done"), "{done}");
    assert!(!out.join(".cota-layout-3.json").exists());
    for i in 0..3 {
        run_ok(&[&base[..], &["-o", o, "--shard", &format!("{i}/3")]].concat());
    }
    run_ok(&["tiles", "-o", o, "--reduce", "--shards", "3"]);
    assert!(
        files(&out) == files(&plain),
        "the plan step in parts gave another pyramid"
    );
    let one = dir.path().join("one");
    let r = run_ok(&[
        "tiles",
        west,
        "-o",
        one.to_str().unwrap(),
        "--plan",
        "--shards",
        "2",
        "--part",
        "1",
    ]);
    assert!(r.contains("reads the whole input"), "{r}");
    let bad = cota(&[&plan[..], &["--part", "3"]].concat());
    assert!(!bad.status.success());
    assert!(stderr(&bad).contains("below 3"), "{}", stderr(&bad));
}
