#![allow(clippy::unwrap_used, clippy::panic)]
use cota_bench::{delatin_mesh, heights_f64, load_cases};
use cota_core::{check_mesh, measure, CheckOptions};
use std::time::Instant;

fn cpu_ms() -> f64 {
    let mut t = 0u64;
    for e in std::fs::read_dir("/proc/self/task").unwrap() {
        let p = e.unwrap().path().join("schedstat");
        if let Ok(s) = std::fs::read_to_string(p) {
            t += s.split_whitespace().next().unwrap().parse::<u64>().unwrap();
        }
    }
    t as f64 / 1e6
}

fn main() {
    let only: Vec<String> = std::env::args().skip(1).collect();
    let es: Vec<f64> = std::env::var("ES")
        .unwrap_or("1,5,20".into())
        .split(',')
        .map(|s| s.parse().unwrap())
        .collect();
    let reps: usize = std::env::var("REPS")
        .map(|s| s.parse().unwrap())
        .unwrap_or(1);
    let cases = load_cases(|m| eprintln!("{m}"));
    for case in &cases {
        if !only.is_empty() && !only.iter().any(|o| o == case.name) {
            continue;
        }
        let g = &case.square;
        let hf = heights_f64(g);
        for &e in &es {
            let (mut tc, mut td) = (f64::INFINITY, f64::INFINITY);
            let mut cpu = f64::INFINITY;
            let mut m = None;
            let mut d = None;
            for _ in 0..reps {
                let t = Instant::now();
                let c0 = cpu_ms();
                if std::env::var("ONLYDEL").is_err() {
                    m = Some(
                        cota_core::tin::build(
                            g,
                            &cota_core::TinOptions::max_error_m(e)
                                .with_lock_border(std::env::var("LOCK").is_ok())
                                .with_bands(
                                    std::env::var("BANDS")
                                        .map(|s| s.parse().unwrap())
                                        .unwrap_or(0),
                                )
                                .with_flips(std::env::var("FLIPS").is_ok())
                                .with_sweeps(
                                    std::env::var("SWEEPS")
                                        .map(|s| s.parse().unwrap())
                                        .unwrap_or(1),
                                ),
                        )
                        .unwrap()
                        .mesh,
                    );
                } else {
                    m = Some(Default::default());
                }
                tc = tc.min(t.elapsed().as_secs_f64() * 1e3);
                cpu = cpu.min(cpu_ms() - c0);
                if std::env::var("NODEL").is_err() {
                    let t = Instant::now();
                    d = Some(delatin_mesh(g, &hf, e).unwrap());
                    td = td.min(t.elapsed().as_secs_f64() * 1e3);
                }
            }
            let m = m.unwrap();
            if std::env::var("NOCHECK").is_ok() {
                println!(
                    "{} E={e}: tin {} {tc:.1} ms, cpu {cpu:.1} ms",
                    case.name,
                    m.triangle_count()
                );
                continue;
            }
            let r = check_mesh(g, &m, &CheckOptions::tin(e)).unwrap_or_else(|x| panic!("{x}"));
            let (dn, de) = d.as_ref().map_or((0, 0.0), |d| {
                (d.triangle_count(), measure(g, d).max_error_m)
            });
            println!("{} E={e}: tin {} ({:.3} m, {tc:.1} ms) delatin {} ({de:.3} m, {td:.1} ms) ratio tris {:.3} time {:.3}",
                case.name, m.triangle_count(), r.metrics.max_error_m, dn, m.triangle_count() as f64 / dn as f64, tc / td);
        }
    }
}
