//! Small validation gaps (issue 23): each flag or input a user trips on gives
//! a clear error naming the flag or the file.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;

use std::path::{Path, PathBuf};

use common::{cota, stderr};

/// Runs `cota ARGS`, expects exit 1 (or 2 for clap) and returns stderr.
fn fails(args: &[&str]) -> String {
    let o = cota(args);
    let err = stderr(&o);
    assert!(matches!(o.status.code(), Some(1 | 2)), "{args:?}: {err}");
    err
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// `ncols`×`nrows` ESRI ASCII grid of `value`, cell `cell`.
fn asc(w: usize, h: usize, cell: &str, value: &str) -> Vec<u8> {
    let values = vec![value; w * h].join(" ");
    format!(
        "ncols {w}\nnrows {h}\nxllcorner 0\nyllcorner 0\ncellsize {cell}\nNODATA_value -9999\n{values}\n"
    )
    .into_bytes()
}

#[test]
fn triangle_budget_error_states_the_true_minimum() {
    let min_of = |n: &str| {
        let err = fails(&["mesh", "--max-triangles", n]);
        let tail = err.split("at least ").nth(1).expect(&err).to_string();
        tail.split_whitespace().next().unwrap().to_string()
    };
    let min = min_of("0");
    assert_eq!(min_of("1"), min);
    assert_eq!(min_of("2"), min);
    let o = cota(&["mesh", "--max-triangles", &min]);
    assert!(o.status.success(), "{min}: {}", stderr(&o));
}

#[test]
fn non_finite_options_are_refused_by_name() {
    for (flag, v) in [
        ("--gray-scale-m", "nan"),
        ("--gray-offset-m", "inf"),
        ("--cell-size-m", "nan"),
    ] {
        let err = fails(&["mesh", flag, v]);
        assert!(
            err.contains(flag) && err.contains("finite"),
            "{flag}: {err}"
        );
    }
}

#[test]
fn zero_directions_are_refused() {
    for flag in ["--look", "--light"] {
        let err = fails(&["mesh", flag, "0,0,0"]);
        assert!(err.contains(flag) && err.contains("not all zero"), "{err}");
    }
}

#[test]
fn negative_numbers_reach_the_range_checks() {
    let err = fails(&["mesh", "--max-error", "-5"]);
    assert!(err.contains("--max-error: expected 0 m or more"), "{err}");
    let err = fails(&["mesh", "--cell-size-m", "-1"]);
    assert!(err.contains("--cell-size-m: expected a positive"), "{err}");
    let err = fails(&[
        "mesh",
        "--criterion",
        "view",
        "--observer",
        "0,0,1",
        "--fov-deg",
        "-5",
    ]);
    assert!(err.contains("--fov-deg"), "{err}");
    assert!(!err.contains("unexpected argument"), "{err}");
    let err = fails(&["mesh", "--max-triangles", "-5"]);
    assert!(!err.contains("unexpected argument"), "{err}");
}

#[test]
fn numbers_print_in_scientific_notation_when_extreme() {
    let err = fails(&["mesh", "--max-error", "-1e300"]);
    assert!(err.contains("-1e300 m"), "{err}");
    let err = fails(&["mesh", "--cell-size-m", "1e-300"]);
    assert!(err.contains("1e-300") && err.len() < 300, "{err}");
}

#[test]
fn errors_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let thin = write(dir.path(), "thin.asc", &asc(65, 1, "1", "5"));
    let err = fails(&["mesh", thin.to_str().unwrap()]);
    assert!(err.contains("thin.asc") && err.contains("65x1"), "{err}");
    let void = write(dir.path(), "void.asc", &asc(3, 3, "1", "-9999"));
    let err = fails(&["mesh", void.to_str().unwrap()]);
    assert!(err.contains("void.asc") && err.contains("void"), "{err}");
}

#[test]
fn underflowing_cell_sizes_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let tiny = write(dir.path(), "tiny.asc", &asc(3, 3, "1e-300", "5"));
    let err = fails(&["mesh", tiny.to_str().unwrap()]);
    assert!(
        err.contains("tiny.asc") && err.contains("cell size"),
        "{err}"
    );
    let err = fails(&["mesh", "--cell-size-m", "1e-300"]);
    assert!(err.contains("--cell-size-m"), "{err}");
}

#[test]
fn a_badly_named_hgt_warns_that_it_has_no_position() {
    let dir = tempfile::tempdir().unwrap();
    let heights: Vec<u8> = (0..9i16).flat_map(|h| (h * 10).to_be_bytes()).collect();
    let foo = write(dir.path(), "foo.hgt", &heights);
    let o = cota(&["info", foo.to_str().unwrap()]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("warning") && err.contains("foo.hgt"), "{err}");
    assert!(err.contains("no position"), "{err}");
    let named = write(dir.path(), "N10E010.hgt", &heights);
    let o = cota(&["info", named.to_str().unwrap()]);
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
}

#[test]
fn compare_help_states_one_default_strip_method() {
    let o = cota(&["compare", "--help"]);
    let help = common::stdout(&o);
    assert!(help.contains("[default: guided]"), "{help}");
    assert!(!help.contains("(the default)"), "{help}");
}

#[test]
fn a_png_without_georeference_reports_its_assumed_cell() {
    let png = common::fixture("terrarium.png");
    let o = cota(&["mesh", png.to_str().unwrap(), "--max-error", "20"]);
    let out = common::stdout(&o);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.contains("cell        assumed 1 m"), "{out}");
    let o = cota(&["mesh", png.to_str().unwrap(), "--max-error", "20", "--json"]);
    let r: serde_json::Value = serde_json::from_str(&common::stdout(&o)).unwrap();
    assert_eq!(r["assumed_cell_size_m"], 1.0);
    let o = cota(&["mesh", "--max-error", "50", "--json"]);
    let r: serde_json::Value = serde_json::from_str(&common::stdout(&o)).unwrap();
    assert!(r["assumed_cell_size_m"].is_null());
}

/// The README lists every command `cota --help` shows, the install step, and
/// git ignores the output of its first command (issue 23).
#[test]
fn readme_lists_every_command_and_its_output_is_ignored() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    assert!(readme.contains("cargo install --path crates/cota-cli"));
    let help = common::stdout(&cota(&["--help"]));
    let commands: Vec<&str> = help
        .split("Commands:")
        .nth(1)
        .unwrap()
        .lines()
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .collect();
    assert!(commands.len() >= 4, "{help}");
    for c in &commands {
        assert!(
            readme.contains(&format!("cota {c} ")),
            "README lacks `cota {c}`"
        );
    }
    let out = readme
        .split("-o ")
        .nth(1)
        .and_then(|t| t.split_whitespace().next())
        .unwrap();
    let ignore = std::fs::read_to_string(root.join(".gitignore")).unwrap();
    assert!(
        ignore.lines().any(|l| l.trim_start_matches('/') == out),
        "{out} not in .gitignore"
    );
}
