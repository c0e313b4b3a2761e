//! The newcomer's paper cuts (issue 33), each replayed on the bundled real
//! DEM (fixtures/S29W072.hgt.zip, SRTM, 29° S 72° W: every coordinate of its
//! box is negative) and on what `cota` writes from it.
#![allow(clippy::unwrap_used, reason = "tests")]

use crate::common;
use common::*;

/// A western and southern box given as `--bbox W,S,E,N` (no `=`): every
/// number starts with a minus sign, and clap must take it as the value.
#[test]
fn negative_numbers_are_values_not_flags() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("box.glb");
    let o = cota(&[
        "mesh",
        "--bbox",
        "-71.9,-28.9,-71.8,-28.8",
        "--max-error",
        "5",
        "--check",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.exists());
    // An observer and a direction below zero, as the view criterion takes them.
    let o = cota(&[
        "mesh",
        "--criterion",
        "view",
        "--observer",
        "-2000,-3000,4000",
        "--look",
        "1,1,-0.3",
        "--max-error-px",
        "3",
    ]);
    let e = stderr(&o);
    assert!(!e.contains("unexpected argument"), "{e}");
    assert!(o.status.success(), "{e}");
}

/// `--error-factor 0`: the message says what was expected in words, not
/// the option's Rust value.
#[test]
fn a_zero_error_factor_is_refused_in_words() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    let o = cota(&["tiles", "--error-factor", "0", "-o", out.to_str().unwrap()]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(!e.contains("Cesium {") && !e.contains("factor:"), "{e}");
    assert!(
        e.contains("expected a positive, finite error factor, found 0"),
        "{e}"
    );
    assert!(!out.exists(), "nothing written");
}

/// `pair` names `--max-samples` when a DEM is over the sample limit: the
/// flag exists on `pair` and raises the limit.
#[test]
fn pair_has_the_flag_its_message_names() {
    let dem = fixture("olinda_dem_utm25s.tif");
    let img = fixture("L7_ETMs.tif");
    let (d, i) = (dem.to_str().unwrap(), img.to_str().unwrap());
    let small = ["pair", d, i, "--bands", "3,2,1", "--budget-bytes", "200000"];
    let o = cota(&[&small[..], &["--max-samples", "1000"]].concat());
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("olinda_dem_utm25s.tif") && e.contains("--max-samples"),
        "{e}"
    );
    let o = cota(&[&small[..], &["--max-samples", "20000"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A stream cut inside a step frame (a partial download) decodes its
/// complete steps and says what is missing; `--strict` refuses it.
#[test]
fn a_cut_stream_decodes_its_complete_steps() {
    let dir = tempfile::tempdir().unwrap();
    let cs = dir.path().join("s.cstream");
    let o = cota(&[
        "stream",
        "encode",
        "-o",
        cs.to_str().unwrap(),
        "--max-error",
        "20",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&cs).unwrap();
    let cut = dir.path().join("cut.cstream");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let mesh = dir.path().join("cut.obj");
    let c = cut.to_str().unwrap();
    let o = cota(&[
        "stream",
        "decode",
        c,
        "-o",
        mesh.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("warning") && e.contains("cut.cstream"), "{e}");
    assert!(e.contains("complete step") && e.contains("missing"), "{e}");
    assert!(mesh.exists());
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert!(
        v["truncated"].as_str().unwrap().contains("truncated"),
        "{v}"
    );
    let whole = cota(&["stream", "decode", cs.to_str().unwrap(), "--json"]);
    let w: serde_json::Value = serde_json::from_str(&stdout(&whole)).unwrap();
    assert!(w["truncated"].is_null());
    assert!(v["steps_used"].as_u64() < w["steps_used"].as_u64());
    let o = cota(&["stream", "decode", c, "--strict"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("truncated"), "{}", stderr(&o));
}

/// The PMTiles input's zoom is `--input-zoom`; `--zoom` still works and
/// warns that it is the input's zoom, not the output's.
#[test]
fn input_zoom_is_named_for_what_it_is() {
    let args = ["info", "--bbox=-72,-29,-71,-28", "--input-zoom", "3"];
    let o = cota(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("deprecated"), "{}", stderr(&o));
    let o = cota(&["info", "--bbox=-72,-29,-71,-28", "--zoom", "3"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("--zoom is deprecated") && e.contains("--input-zoom"),
        "{e}"
    );
}

/// Negative numbers in a crop are refused by the crop's own message, not by
/// clap's "unexpected argument" with its `-- -7` tip.
#[test]
fn negative_crop_is_refused_by_its_own_message() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.obj");
    let o = cota(&["mesh", "--crop", "-1,0,10,10", "-o", out.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(!o.status.success());
    assert!(!e.contains("unexpected argument"), "{e}");
    assert!(e.contains("COL,ROW,W,H"), "{e}");
    assert!(!out.exists());
}

/// An output that cannot be made: the operating system's text once, not
/// once from the wrapping error and again from its cause.
#[test]
fn os_error_text_is_printed_once() {
    let o = cota(&[
        "tiles",
        "--max-zoom",
        "3",
        "-o",
        "/proc/cota-cannot-make-this",
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("/proc/cota-cannot-make-this"), "{e}");
    assert_eq!(e.matches("(os error").count(), 1, "{e}");
}

/// `--mesh tin` on 1 and on 2 threads: the same mesh, byte for byte, and a
/// reported largest error that a script can test against the bound
/// (`max_error_m <= 1`), as the checker does.
#[test]
fn the_tin_is_the_same_on_any_thread_count_and_its_error_never_reads_above_the_bound() {
    let dir = tempfile::tempdir().unwrap();
    let run = |threads: &str| {
        let out = dir.path().join(format!("tin{threads}.obj"));
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_cota"))
            .env("RAYON_NUM_THREADS", threads)
            .args([
                "mesh",
                "--mesh",
                "tin",
                "--max-error",
                "1",
                "--check",
                "--json",
                "-o",
            ])
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        let r: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        let max = r["max_error_m"].as_f64().unwrap();
        assert!(max <= 1.0, "reported {max} m for a bound of 1 m");
        (
            std::fs::read(&out).unwrap(),
            r["triangles"].as_u64().unwrap(),
        )
    };
    let (one, n1) = run("1");
    let (two, n2) = run("2");
    assert_eq!(n1, n2, "triangles on 1 and 2 threads");
    assert!(one == two, "the TIN differs between 1 and 2 threads");
}

/// Outputs that cannot be written are refused before any work (before the
/// input is even opened: it does not exist here), each path named once: a directory where no file can be made (`/proc`), a file in
/// the way of a tiles directory, a tiles directory under a file.
#[test]
fn outputs_are_refused_before_any_work_and_named_once() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a-file");
    std::fs::write(&file, b"x").unwrap();
    let file_s = file.to_str().unwrap();
    let under = format!("{file_s}/tiles");
    let cases: Vec<(Vec<&str>, String)> = vec![
        (
            vec!["tiles", "-o", file_s],
            format!("cannot write {file_s}: expected a directory, found a file"),
        ),
        (
            vec!["tiles", "-o", &under],
            format!("cannot write {under}: {file_s} is not a directory"),
        ),
    ];
    let proc_cases: Vec<(Vec<&str>, String)> = if std::path::Path::new("/proc/self").is_dir() {
        vec![
            (
                vec!["mesh", "-o", "/proc/x.glb"],
                "cannot write /proc/x.glb: cannot create a file in /proc".into(),
            ),
            (
                vec!["tiles", "-o", "/proc/x"],
                "cannot write /proc/x: cannot create a file in /proc".into(),
            ),
            (
                vec!["stream", "encode", "-o", "/proc/x.cota"],
                "cannot write /proc/x.cota: cannot create a file in /proc".into(),
            ),
        ]
    } else {
        eprintln!("skipped: /proc cases (no /proc here)");
        vec![]
    };
    for (mut args, want) in cases.into_iter().chain(proc_cases) {
        // An input that does not exist: the output must be refused first.
        args.insert(args.len() - 2, "no-such-dem.hgt");
        let o = cota(&args);
        let e = stderr(&o);
        assert!(!o.status.success(), "{args:?}");
        assert!(e.contains(&want), "{args:?}: {e}");
        assert!(
            !e.contains("at path"),
            "{args:?}: a temporary path leaked: {e}"
        );
        let first = e.find(args[args.len() - 1]).unwrap();
        assert!(
            !e[first + 1..].contains(&format!("{}:", args[args.len() - 1])),
            "{args:?}: the path is printed twice: {e}"
        );
    }
}

/// The README's commands that take a DEM, as written there (its first
/// command, `cargo run --release --bin cota -- mesh …`, and its 3D-printing
/// command), on the bundled coastal tile (sea at 0 m, where `--base-m 0`
/// was refused) and on every shared DEM: each succeeds (the first with its
/// `--check`), the print a closed STL whose base lies 2 mm below its lowest
/// point. The only flag added is the one a file needs by its nature (the
/// Puget Sound PNG's 0.1 m per gray level, DATA.md). `--base-m 0` on the
/// coast is refused before any meshing, naming the flag that fits.
#[test]
fn the_readme_commands_work_on_every_dem_coast_included() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md")).unwrap();
    let first = readme
        .lines()
        .find(|l| l.starts_with("cargo run --release --bin cota -- "))
        .expect("the README's first command");
    let first: Vec<&str> = first
        .split(" -- ")
        .nth(1)
        .unwrap()
        .split_whitespace()
        .collect();
    assert_eq!(first[0], "mesh", "{first:?}");
    let line = readme
        .lines()
        .find(|l| l.contains("**3D printing**"))
        .expect("the README's 3D printing line");
    let cmd = line.split('`').nth(1).expect("a command in backticks");
    let print: Vec<&str> = cmd.split_whitespace().collect();
    assert_eq!(&print[..2], ["cota", "mesh"], "{cmd}");
    let mut dems = vec![(fixture("S29W072.hgt.zip"), None)];
    let shared_dems = [
        "srtm/N00E010.hgt",
        "srtm/N00E011.hgt.zip",
        "srtm/N41E001.hgt.zip",
        "srtm/N42E001.hgt.zip",
        "srtm/N49E011.hgt.zip",
        "srtm/N50E011.hgt.zip",
        "asc/hugo_site.asc",
        "asc/bijou_gully_subset_5m_edit_dx_filled.asc",
        "asc/boulder_srtmgl3_240x144.asc",
        "geotiff/dem-hills.tiff",
        "geotiff/luxembourg_elev_terra.tif",
        "geotiff/mapzen-geotiff-14-10348-7801.tif",
        "geotiff/mt_fuji_90m.tif",
        "geotiff/sanfrancisco_rio_rgbify.tif",
        "png/fuji.png",
        "png/ps_height_1k.png",
        "png/terrarium.png",
        "texture/olinda_dem_utm25s.tif",
    ];
    for rel in shared_dems {
        let needs = rel.contains("ps_height").then_some("--gray-scale-m=0.1");
        match shared(rel) {
            Some(p) => dems.push((p, needs)),
            None => eprintln!("skipped: {rel} (shared data absent)"),
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let run = |words: &[&str], dem: &std::path::Path, needs: Option<&str>, out: &str| {
        let mut args: Vec<String> = words.iter().map(|w| w.to_string()).collect();
        let o_at = args.iter().position(|w| w == "-o").unwrap();
        args[o_at + 1] = dir.path().join(out).to_str().unwrap().to_string();
        args.insert(1, dem.to_str().unwrap().to_string());
        args.extend(needs.map(String::from));
        args.push("--json".into());
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = cota(&refs);
        assert!(
            o.status.success(),
            "{}: {args:?}: {}",
            dem.display(),
            stderr(&o)
        );
        serde_json::from_str::<serde_json::Value>(&stdout(&o)).unwrap()
    };
    for (dem, needs) in &dems {
        let r = run(&first, dem, *needs, "sample.glb");
        assert_eq!(r["checked"], true, "{}: {r}", dem.display());
        assert!(
            r["max_error_m"].as_f64().unwrap() <= 5.0,
            "{}: {r}",
            dem.display()
        );
        let r = run(&print[1..], dem, *needs, "model.stl");
        let z_mm = r["print_size_mm"][2].as_f64().unwrap();
        assert!(z_mm > 2.0 - 1e-9, "{}: {z_mm} mm high", dem.display());
        assert!(
            std::fs::metadata(dir.path().join("model.stl"))
                .unwrap()
                .len()
                > 1000
        );
    }
    let o = cota(&[
        "mesh",
        "-o",
        dir.path().join("x.stl").to_str().unwrap(),
        "--base-m",
        "0",
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("--base-m: expected a base below the lowest sample (-5 m), found 0 m")
            && e.contains("--base-mm"),
        "{e}"
    );
}

/// Numbers in reports to a sensible precision: a bound of 1e300 m is not
/// printed as 301 digits, a print scale from `--size-mm` is a whole 1:N.
#[test]
fn numbers_are_printed_to_a_sensible_precision() {
    let o = cota(&["mesh", "--max-error", "1e300"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let t = stdout(&o);
    assert!(
        t.contains("(bound 1e300 m)") && t.contains("max-error 1e300 m"),
        "{t}"
    );
    assert!(!t.contains("000000000000"), "{t}");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.stl");
    let o = cota(&[
        "mesh",
        "--size-mm",
        "150",
        "--base-mm",
        "2",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let t = stdout(&o);
    let line = t.lines().find(|l| l.starts_with("print")).unwrap();
    let scale = line.split_whitespace().nth(1).unwrap();
    assert!(
        scale.starts_with("1:") && scale[2..].chars().all(|c| c.is_ascii_digit()),
        "{line}"
    );
    assert!(line.contains("(0.001353 mm per m)"), "{line}");
}

/// `--quiet` silences everything but errors: no text report from mesh,
/// tiles, stream encode or compare; a report asked for with `--json` is
/// still printed; an error still is.
#[test]
fn quiet_silences_the_report_but_not_json_or_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let (glb, tiles, stream) = (d("m.glb"), d("t"), d("s.cota"));
    for args in [
        vec!["--quiet", "mesh", "--max-error", "20", "-o", &glb],
        vec!["--quiet", "tiles", "--max-zoom", "6", "-o", &tiles],
        vec![
            "--quiet",
            "stream",
            "encode",
            "--max-error",
            "50",
            "-o",
            &stream,
        ],
    ] {
        let o = cota(&args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        assert_eq!(stdout(&o), "", "{args:?}");
        let e = stderr(&o);
        assert!(e.lines().all(|l| l.contains("warning")), "{args:?}: {e}");
    }
    let o = cota(&["--quiet", "mesh", "--max-error", "20", "--json"]);
    let r: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert!(r["triangles"].as_u64().unwrap() > 0);
    let o = cota(&["--quiet", "mesh", "--max-error", "-1"]);
    assert!(!o.status.success() && stderr(&o).contains("error"));
}

/// The early output check refuses what cannot be written, not what is only
/// new: an archive or a directory under directories that do not exist yet
/// is made.
#[test]
fn new_output_directories_are_made_not_refused() {
    let dir = tempfile::tempdir().unwrap();
    for out in [
        dir.path().join("a/b/t.mbtiles"),
        dir.path().join("c/d/tiles"),
    ] {
        let o = cota(&["tiles", "--max-zoom", "3", "-o", out.to_str().unwrap()]);
        assert!(o.status.success(), "{}: {}", out.display(), stderr(&o));
        assert!(out.exists(), "{}", out.display());
    }
}

/// Heights beyond ±12,000 m (here a real grid, fixtures/hugo_site.asc,
/// raised by 2·10⁷ m, where f32 holds heights only to the metre) are
/// refused, naming the file, the sample and the flag; `--any-height`
/// accepts them and says how precisely they are held.
#[test]
fn absurd_heights_are_refused_naming_the_file_and_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(fixture("hugo_site.asc")).unwrap();
    let mut raised = String::new();
    for line in text.lines() {
        let header = line
            .split_whitespace()
            .next()
            .is_some_and(|w| w.chars().next().is_some_and(char::is_alphabetic));
        if header {
            raised.push_str(line);
        } else {
            let vals: Vec<String> = line
                .split_whitespace()
                .map(|v| {
                    let h: f64 = v.parse().unwrap();
                    if h < -9000.0 {
                        v.to_string()
                    } else {
                        format!("{:.3}", h + 2e7)
                    }
                })
                .collect();
            raised.push_str(&vals.join(" "));
        }
        raised.push('\n');
    }
    let input = dir.path().join("raised.asc");
    std::fs::write(&input, raised).unwrap();
    let out = dir.path().join("m.obj");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let r = cota(&["mesh", i, "--max-error", "0.5", "-o", o]);
    assert!(!r.status.success());
    let e = stderr(&r);
    for want in ["raised.asc", "within ±12000 m", "found 200", "--any-height"] {
        assert!(e.contains(want), "{want:?} not in: {e}");
    }
    assert!(!out.exists());
    let r = cota(&["mesh", i, "--any-height", "--max-error", "0.5", "-o", o]);
    let e = stderr(&r);
    assert!(r.status.success(), "{e}");
    assert!(e.contains("held as f32, within 1.00 m"), "{e}");
    let r = cota(&["info", fixture("hugo_site.asc").to_str().unwrap()]);
    assert!(r.status.success() && !stderr(&r).contains("held as f32"));
}

/// The commands that read DEMs.
const READING_COMMANDS: [&[&str]; 7] = [
    &["info"],
    &["mesh"],
    &["compare"],
    &["pair"],
    &["stream", "encode"],
    &["tiles"],
    &["serve"],
];

/// One set of reading flags (item 9): every command that reads DEMs lists
/// the same flags under one heading, `--crop` and `--bbox` included (`pair`
/// had only `--max-samples`, `--crop` was on `mesh` and `compare` only).
#[test]
fn every_command_that_reads_dems_takes_one_set_of_reading_flags() {
    let flags = [
        "--encoding",
        "--gray-scale-m",
        "--gray-offset-m",
        "--cell-size-m",
        "--band",
        "--array",
        "--input-zoom",
        "--bbox",
        "--crop",
        "--seam",
        "--seam-tolerance",
        "--strict",
        "--max-samples",
        "--src-crs",
    ];
    for cmd in READING_COMMANDS {
        let o = cota(&[cmd, &["--help"]].concat());
        assert!(o.status.success(), "{cmd:?}");
        let help = stdout(&o);
        assert!(
            help.contains("Reading DEMs:"),
            "{cmd:?}: no heading:\n{help}"
        );
        let section = help.split("Reading DEMs:").nth(1).unwrap();
        for f in flags {
            let listed = [" ", "\n", "="].iter().any(|end| {
                section.contains(&format!("  {f}{end}")) || section.contains(&format!(", {f}{end}"))
            });
            assert!(listed, "{cmd:?} lacks {f} among its reading flags:\n{help}");
        }
    }
}

/// `--crop` keeps the same window on every command: `info` and `stream
/// encode` report its size, `tiles` makes the tiles of the window only,
/// `pair` drapes the image on the window.
#[test]
fn crop_is_the_same_window_on_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let crop = ["--crop", "100,200,65,33"];
    let o = cota(&[&["info", "--json"][..], &crop].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(65), Some(33))
    );
    let cs = dir.path().join("c.cstream");
    let args = ["stream", "encode", "--max-error", "20", "--json", "-o"];
    let o = cota(&[&args[..], &[cs.to_str().unwrap()], &crop].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(65), Some(33))
    );
    let tiles = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let args = [
            "tiles",
            "--max-zoom",
            "9",
            "--json",
            "-o",
            out.to_str().unwrap(),
        ];
        let o = cota(&[&args[..], extra].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        v["tiles"].as_u64().unwrap()
    };
    let (whole, window) = (tiles("whole", &[]), tiles("window", &crop));
    assert!(
        window < whole,
        "{window} tiles for the window, {whole} for the whole"
    );
    let dem = fixture("olinda_dem_utm25s.tif");
    let img = fixture("L7_ETMs.tif");
    let pair = |extra: &[&str]| {
        let args = ["pair", dem.to_str().unwrap(), img.to_str().unwrap()];
        let more = ["--bands", "3,2,1", "--budget-bytes", "200000", "--json"];
        let o = cota(&[&args[..], &more, extra].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        v["image"]["texture_size"].clone()
    };
    let (full, cut) = (pair(&[]), pair(&["--crop", "0,0,40,30"]));
    assert_ne!(full, cut);
    assert!(cut[0].as_u64() < full[0].as_u64(), "{cut} vs {full}");
}

/// `compare --tolerances`: plain numbers are metres, `%` marks a percentage
/// of the height range, a list may mix them, and each row says which.
#[test]
fn compare_tolerances_are_metres_unless_marked_percent() {
    let base = [
        "compare",
        "--crop",
        "824,792,65,65",
        "--modes",
        "conforming",
        "--quadtree",
        "templates",
        "--tolerances",
        "5,10%",
    ];
    let o = cota(&[&base[..], &["--json"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let range = v["range_m"].as_f64().unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[1]["label"], "5 m");
    assert_eq!(rows[1]["tolerance_given_in"], "metres");
    assert_eq!(rows[1]["tolerance_m"].as_f64(), Some(5.0));
    assert!((rows[1]["tolerance_pct"].as_f64().unwrap() - 500.0 / range).abs() < 1e-9);
    assert_eq!(rows[2]["label"], "10%");
    assert_eq!(rows[2]["tolerance_given_in"], "percent_of_range");
    assert!((rows[2]["tolerance_m"].as_f64().unwrap() - 0.1 * range).abs() < 1e-9);
    for e in rows[1]["entries"].as_array().unwrap() {
        assert!(e["max_error_m"].as_f64().unwrap() <= 5.0);
    }
    let o = cota(&base);
    assert!(o.status.success(), "{}", stderr(&o));
    let t = stdout(&o);
    assert!(t.contains("| 5 m | 5.0 |") && t.contains("| 10% |"), "{t}");
    for bad in ["-1", "5%%", "x", "inf%"] {
        let o = cota(&["compare", "--tolerances", bad]);
        assert!(!o.status.success(), "{bad}");
        let e = stderr(&o);
        assert!(e.contains("percentage of the height range"), "{bad}: {e}");
    }
}

/// `tiles` reads a PMTiles archive's zoom as `--input-zoom`, like every
/// command; `--zoom` still works there and warns.
#[test]
fn tiles_takes_input_zoom_and_warns_on_the_old_name() {
    let o = cota(&["tiles", "--help"]);
    assert!(stdout(&o).contains("--input-zoom <Z>"), "{}", stdout(&o));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    let args = ["tiles", "--bbox=-72,-29,-71,-28", "--max-zoom", "4", "-o"];
    let o = cota(&[&args[..], &[out.to_str().unwrap(), "--zoom", "3"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("--zoom is deprecated") && e.contains("--input-zoom"),
        "{e}"
    );
}

/// The figures of a `cota tiles --json` estimate line: tiles, memory (MB).
fn estimate_of(stderr: &str) -> (f64, f64) {
    assert!(stderr.contains("cota: estimate: "), "no estimate: {stderr}");
    let line = stderr
        .lines()
        .find(|l| l.starts_with("cota: estimate: "))
        .unwrap();
    let words: Vec<&str> = line.split_whitespace().collect();
    let tiles: f64 = words[2].parse().unwrap();
    let at = words.iter().position(|w| *w == "memory").unwrap();
    let (n, unit) = (words[at - 3], words[at - 2]);
    let scale = if unit == "GB" { 1e3 } else { 1.0 };
    (tiles, n.parse::<f64>().unwrap() * scale)
}

/// `tiles` says what it will make before it starts (item 11): the tiles
/// (here exactly those made), the lattice and the memory; past 10^6 tiles
/// or the memory available it refuses without `--yes`, naming it, before
/// any work; `--quiet` silences the estimate.
#[test]
fn tiles_estimates_before_it_starts_and_asks_for_yes_past_the_limits() {
    let dir = tempfile::tempdir().unwrap();
    let out = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let o = cota(&["tiles", "--max-zoom", "8", "--json", "-o", &out("a")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let (tiles, mb) = estimate_of(&stderr(&o));
    assert_eq!(tiles, v["tiles"].as_f64().unwrap());
    assert!((30.0..200.0).contains(&mb), "{mb} MB");
    assert!(stderr(&o).contains("tiles at zooms 0 to 8; a lattice of"));
    // 2.8 M tiles at zoom 18 on one 3" tile.
    let t0 = std::time::Instant::now();
    let o = cota(&["tiles", "--max-zoom", "18", "-o", &out("b")]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("M tiles (more than 1.0 M)") && e.contains("--yes"),
        "{e}"
    );
    assert!(
        t0.elapsed().as_secs() < 30,
        "refused only after {:?}",
        t0.elapsed()
    );
    assert!(!std::path::Path::new(&out("b")).join("layer.json").exists());
    // Few tiles, but a lattice of 4096 cells a tile at zoom 14: terabytes.
    let big = ["tiles", "--max-zoom", "14", "--tile-cells", "4096", "-o"];
    let o = cota(&[&big[..], &[&out("c")]].concat());
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("of memory (more than the") && e.contains("--yes"),
        "{e}"
    );
    assert!(!e.contains("tiles (more than"), "{e}");
    // --yes goes on (to the lattice's own size limit here).
    let o = cota(&[&big[..], &[&out("d"), "--yes"]].concat());
    let e = stderr(&o);
    assert!(
        e.contains("going on past") && !e.contains("expected --yes"),
        "{e}"
    );
    let o = cota(&["--quiet", "tiles", "--max-zoom", "3", "-o", &out("e")]);
    assert!(
        o.status.success() && !stderr(&o).contains("estimate"),
        "{}",
        stderr(&o)
    );
}
