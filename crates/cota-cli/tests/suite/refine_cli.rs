//! `cota mesh --mode … --criterion …` on the bundled sample: the checker
//! passes, the JSON has the point counts, bad flags are refused.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;
use common::*;

fn json(o: &std::process::Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_str(&stdout(o)).unwrap()
}

#[test]
fn fictitious_modes_check_and_transmit_fewer_points() {
    let run = |mode: &str| {
        json(&cota(&[
            "mesh",
            "--max-error",
            "15",
            "--mode",
            mode,
            "--check",
            "--json",
        ]))
    };
    let c = run("conforming");
    let f = run("fictitious");
    let ff = run("fictitious-faithful");
    for (r, mode) in [
        (&c, "conforming"),
        (&f, "fictitious"),
        (&ff, "fictitious-faithful"),
    ] {
        assert_eq!(r["mode"], mode);
        assert_eq!(r["checked"], true);
        assert!(r["max_error_m"].as_f64().unwrap() <= 15.0);
        assert_eq!(
            r["transmitted_points"].as_u64().unwrap() + r["fictitious_points"].as_u64().unwrap(),
            r["vertices"].as_u64().unwrap()
        );
        assert!(r["criterion"].as_str().unwrap().starts_with("max-error"));
    }
    assert_eq!(c["fictitious_points"], 0);
    assert_eq!(f["line_triangles"], 0);
    assert!(ff["line_triangles"].as_u64().unwrap() > 0);
    assert!(f["transmitted_points"].as_u64() < c["transmitted_points"].as_u64());
    assert!(ff["transmitted_points"].as_u64() < c["transmitted_points"].as_u64());
}

#[test]
fn every_criterion_runs_from_the_command_line() {
    let obs = ["--observer", "20000,20000,3000", "--look", "1,1,-0.3"];
    let cases: Vec<Vec<&str>> = vec![
        vec!["--criterion", "euclidean", "--max-error", "20"],
        vec!["--criterion", "size", "--size-factor", "0.05"],
        vec!["--criterion", "curvature"],
        vec!["--criterion", "light", "--alpha", "0.2", "--light", "1,0,1"],
        [
            &["--criterion", "view", "--max-error-px", "3"][..],
            &obs[..],
        ]
        .concat(),
        [&["--criterion", "paper001"][..], &obs[..]].concat(),
        [&["--criterion", "paper003"][..], &obs[..]].concat(),
    ];
    for extra in cases {
        for mode in ["conforming", "fictitious-faithful"] {
            let mut args = vec!["mesh", "--check", "--json", "--mode", mode];
            args.extend(extra.iter().copied());
            let r = json(&cota(&args));
            assert!(r["triangles"].as_u64().unwrap() >= 2, "{args:?}");
            assert_eq!(r["mode"], mode);
        }
    }
}

#[test]
fn bad_refinement_flags_are_refused() {
    for args in [
        &["mesh", "--criterion", "view"][..],
        &["mesh", "--mode", "fictitious", "--max-triangles", "1000"][..],
        &["mesh", "--criterion", "light", "--alpha", "1.5"][..],
        &["mesh", "--criterion", "view", "--observer", "1,2"][..],
        &["mesh", "--criterion", "nope"][..],
    ] {
        let o = cota(args);
        assert!(!o.status.success(), "{args:?} should fail");
        assert!(!stderr(&o).is_empty());
    }
}
