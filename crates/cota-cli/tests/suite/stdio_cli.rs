//! Standard input and output (issue 23, item 7): `-` reads one DEM from
//! stdin (detected from its content, within --max-samples), `-o -` writes
//! a mesh to stdout (with --format; the report then goes to stderr).
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;

use std::io::Write;
use std::process::{Command, Output, Stdio};

use common::{fixture, stderr, stdout};

/// Runs `cota ARGS` with `input` on its standard input.
fn with_stdin(args: &[&str], input: &[u8]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_cota"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    // A refused input may close the pipe early: a write error is fine.
    let _ = stdin.write_all(input);
    drop(stdin);
    child.wait_with_output().unwrap()
}

fn sample() -> Vec<u8> {
    std::fs::read(fixture("S29W072.hgt.zip")).unwrap()
}

#[test]
fn info_reads_a_zipped_tile_from_stdin() {
    let o = with_stdin(&["info", "-", "--json"], &sample());
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let text = v.to_string();
    assert!(text.contains("<stdin>"), "{text}");
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(1201), Some(1201)),
        "{text}"
    );
}

#[test]
fn a_raw_hgt_on_stdin_is_known_by_its_size() {
    let s = cota_fixtures::bundled_tile();
    let raw: Vec<u8> = s
        .heights
        .iter()
        .flat_map(|h| (*h as i16).to_be_bytes())
        .collect();
    assert_eq!(raw.len(), 2 * 1201 * 1201);
    let o = with_stdin(&["info", "-"], &raw);
    let out = stdout(&o);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        out.contains("1201 x 1201") || out.contains("1201x1201"),
        "{out}"
    );
    // Without a name there is no position: said, as for a badly named file.
    assert!(stderr(&o).contains("<stdin>"), "{}", stderr(&o));
}

#[test]
fn stdin_keeps_the_memory_limits_and_names_itself() {
    let o = with_stdin(&["info", "-", "--max-samples", "1000"], &sample());
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("<stdin>") && err.contains("too large"),
        "{err}"
    );
    let o = with_stdin(&["info", "-"], b"hello, not a DEM");
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("<stdin>") && err.contains("expected"), "{err}");
    // A raw .hgt of another size needs the name that stdin lacks: said so.
    let o = with_stdin(&["info", "-"], &vec![0u8; 2 * 100 * 100]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("no extension") && err.contains("1201"),
        "{err}"
    );
    let other = fixture("S29W072.hgt.zip");
    let o = with_stdin(&["info", "-", other.to_str().unwrap()], &sample());
    assert!(stderr(&o).contains("the only FILE"), "{}", stderr(&o));
}

#[test]
fn mesh_from_stdin_to_stdout() {
    let args = [
        "mesh",
        "-",
        "--max-error",
        "30",
        "-o",
        "-",
        "--format",
        "obj",
    ];
    let o = with_stdin(&args, &sample());
    assert!(o.status.success(), "{}", stderr(&o));
    let obj = stdout(&o);
    assert!(obj.starts_with("# "), "{}", &obj[..obj.len().min(200)]);
    assert!(obj.lines().any(|l| l.starts_with("f ")));
    assert!(!obj.contains("mesh        "), "the report went to stdout");
    assert!(stderr(&o).contains("mesh        "), "{}", stderr(&o));
    // The same mesh as written to a file.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("m.obj");
    let f = common::cota(&["mesh", "--max-error", "30", "-o", file.to_str().unwrap()]);
    assert!(f.status.success(), "{}", stderr(&f));
    let written = std::fs::read_to_string(&file).unwrap();
    let body = |s: &str| {
        s.lines()
            .filter(|l| !l.starts_with('#'))
            .map(str::to_owned)
            .collect::<Vec<_>>()
    };
    assert_eq!(body(&obj), body(&written));
    // GLB to a pipe; the JSON report on stderr.
    let args = [
        "mesh",
        "--max-error",
        "30",
        "-o",
        "-",
        "--format",
        "glb",
        "--json",
    ];
    let o = with_stdin(&args, b"");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(o.stdout.starts_with(b"glTF"));
    let report: serde_json::Value = serde_json::from_str(&stderr(&o)).unwrap();
    assert_eq!(report["output"], "-");
}

#[test]
fn stdout_needs_a_format_that_agrees() {
    let o = common::cota(&["mesh", "-o", "-"]);
    assert!(stderr(&o).contains("--format"), "{}", stderr(&o));
    assert_eq!(o.status.code(), Some(1));
    let o = common::cota(&["mesh", "-o", "x.obj", "--format", "glb"]);
    assert!(stderr(&o).contains("disagrees"), "{}", stderr(&o));
    let dir = tempfile::tempdir().unwrap();
    let cs = dir.path().join("s.cstream");
    let o = common::cota(&["stream", "encode", "-o", "-"]);
    assert!(stderr(&o).contains("-o -"), "{}", stderr(&o));
    let e = common::cota(&[
        "stream",
        "encode",
        "--max-error",
        "20",
        "-o",
        cs.to_str().unwrap(),
    ]);
    assert!(e.status.success(), "{}", stderr(&e));
    let o = with_stdin(
        &[
            "stream",
            "decode",
            cs.to_str().unwrap(),
            "-o",
            "-",
            "--format",
            "ply",
        ],
        b"",
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(o.stdout.starts_with(b"ply\n"));
    assert!(stderr(&o).contains("wrote       -"), "{}", stderr(&o));
}

/// A reader that stops early (`| head`) ends the run quietly, exit 0.
#[test]
fn a_closed_stdout_stops_quietly() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_cota"))
        .args(["mesh", "--max-error", "1", "-o", "-", "--format", "obj"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = child.stdout.take().unwrap();
    let mut head = [0u8; 16];
    std::io::Read::read_exact(&mut out, &mut head).unwrap();
    drop(out);
    let o = child.wait_with_output().unwrap();
    assert!(head.starts_with(b"# "));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("error"), "{}", stderr(&o));
}

/// `cota pair - IMAGE` reads the DEM from stdin; `-o -` writes the GLB to
/// stdout, the report to stderr.
#[test]
fn pair_reads_the_dem_from_stdin_and_writes_stdout() {
    let dem = std::fs::read(fixture("olinda_dem_utm25s.tif")).unwrap();
    let img = fixture("L7_ETMs.tif");
    let args = [
        "pair",
        "-",
        img.to_str().unwrap(),
        "--bands",
        "3,2,1",
        "--budget-bytes",
        "100000",
        "-o",
        "-",
    ];
    let o = with_stdin(&args, &dem);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(o.stdout.starts_with(b"glTF"));
    assert!(o.stdout.len() <= 100_000);
    assert!(
        stderr(&o).contains("<stdin>") || stderr(&o).contains("dem         -"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn stream_decode_reads_standard_input_within_its_limits() {
    let dir = tempfile::tempdir().unwrap();
    let cs = dir.path().join("s.cstream");
    let c = cs.to_str().unwrap();
    let o = common::cota(&["stream", "encode", "--max-error", "10", "-o", c]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&cs).unwrap();
    let from_file = common::cota(&["stream", "decode", c, "-o", "-", "--format", "obj"]);
    assert!(from_file.status.success(), "{}", stderr(&from_file));
    let o = with_stdin(
        &["stream", "decode", "-", "-o", "-", "--format", "obj"],
        &bytes,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(o.stdout.len() > 1000);
    assert_eq!(o.stdout, from_file.stdout);
    // A prefix by bytes, and the whole input still counted.
    let o = with_stdin(
        &["stream", "decode", "-", "--max-bytes", "20000", "--json"],
        &bytes,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["file_bytes"].as_u64(), Some(bytes.len() as u64), "{v}");
    // The head's grid (1201² samples) over --max-samples: refused by name.
    let o = with_stdin(&["stream", "decode", "-", "--max-samples", "1000"], &bytes);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("<stdin>") && e.contains("too large"), "{e}");
    assert!(
        e.contains("1201×1201") && e.contains("--max-samples"),
        "{e}"
    );
}
