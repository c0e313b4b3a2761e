//! Fictitious-point mode (paper 000 §2.2): the checker on every mode on real
//! data, the dependency rules on hand-made grids, and the transmission saving.
#![allow(clippy::unwrap_used, reason = "tests")]

use crate::common;

use cota_core::hierarchy::Hierarchy;
use cota_core::mesh::check::Violation;
use cota_core::refine::Marks;
use cota_core::refine::{refine, triangulate, Mode, RefineOptions, Refined};
use cota_core::{
    check_mesh, Bitree, CheckOptions, ExtractOptions, GeoRef, HeightGrid, MaxVerticalError,
    MeshError,
};

const MODES: [Mode; 3] = [
    Mode::Conforming,
    Mode::Fictitious { watertight: true },
    Mode::Fictitious { watertight: false },
];

fn real() -> HeightGrid {
    common::tile()
}

fn check_opts(mode: Mode, e: f64) -> CheckOptions {
    CheckOptions::conforming(e)
        .with_conforming(mode.is_conforming())
        .with_allow_fictitious(mode != Mode::Conforming)
}

fn run(g: &HeightGrid, e: f64, mode: Mode) -> Refined {
    let r = refine(
        g,
        &MaxVerticalError { max_error_m: e },
        &RefineOptions::DEFAULT.with_mode(mode),
    )
    .unwrap();
    let rep = check_mesh(g, &r.mesh, &check_opts(mode, e));
    assert!(rep.is_ok(), "{} e={e}: {:?}", mode.name(), rep.err());
    assert_eq!(
        r.transmitted_points + r.fictitious_points,
        r.mesh.vertex_count()
    );
    r
}

fn grid(w: usize, h: usize, mut f: impl FnMut(usize, usize) -> f32) -> HeightGrid {
    let v = (0..w * h).map(|i| f(i % w, i / w)).collect();
    HeightGrid::new(w, h, v, GeoRef::unreferenced(1.0)).unwrap()
}

#[test]
fn every_mode_passes_the_checker_on_real_data_and_fictitious_transmits_fewer() {
    let g = real();
    let tin = Bitree::build(&g).unwrap();
    for e in [5.0, 20.0] {
        let fast = tin.extract(&ExtractOptions::max_error_m(e)).unwrap().mesh;
        let c = run(&g, e, Mode::Conforming);
        let wt = run(&g, e, Mode::Fictitious { watertight: true });
        let fa = run(&g, e, Mode::Fictitious { watertight: false });
        eprintln!(
            "S29W072 {}x{} e={e} m: error map {} vertices / {} triangles; conforming {} transmitted / {} triangles ({} rounds); \
             fictitious {} transmitted + {} fictitious / {} triangles; faithful {} transmitted + {} fictitious / {} triangles, {} line triangles",
            g.width(), g.height(), fast.vertex_count(), fast.triangle_count(),
            c.transmitted_points, c.mesh.triangle_count(), c.rounds,
            wt.transmitted_points, wt.fictitious_points, wt.mesh.triangle_count(),
            fa.transmitted_points, fa.fictitious_points, fa.mesh.triangle_count(), fa.line_triangles,
        );
        assert_eq!(c.fictitious_points, 0);
        assert_eq!(c.line_triangles, 0);
        assert_eq!(wt.line_triangles, 0);
        assert!(wt.fictitious_points > 0 && fa.fictitious_points > 0);
        assert!(wt.transmitted_points < c.transmitted_points);
        assert!(fa.transmitted_points < c.transmitted_points);
        assert!(fa.line_triangles > 0);
        // The watertight variant splits neighbours only through fictitious
        // points: at most as many points sent as the faithful one needs... both
        // are valid; and the faithful one has fewer triangles.
        assert!(fa.mesh.triangle_count() <= wt.mesh.triangle_count());
    }
}

#[test]
fn small_grids_every_mode_every_bound() {
    for (w, h) in [(2, 2), (3, 2), (5, 5), (9, 9), (17, 10), (33, 33), (40, 23)] {
        let g = grid(w, h, |x, y| {
            let (x, y) = (x as f32, y as f32);
            30.0 * (x * 0.7).sin() * (y * 0.45).cos()
                + ((x as usize * 7 + y as usize * 13) % 5) as f32
        });
        for e in [0.0, 0.5, 3.0, 100.0] {
            for m in MODES {
                run(&g, e, m);
            }
        }
    }
}

/// A 5×5 grid (padded square N = 4) with distinct heights.
fn five() -> HeightGrid {
    grid(5, 5, |x, y| (x * 3 + y * 7 + x * y) as f32)
}

fn marks_with(g: &HeightGrid, mode: Mode, selected: &[[u32; 2]]) -> Marks {
    let mut m = Marks::new(Hierarchy::new(g.width() as u32, g.height() as u32), mode);
    m.seed_border();
    for &p in selected {
        m.select(p);
    }
    m.close();
    m
}

fn present(m: &Marks, g: &HeightGrid) -> (Vec<[u32; 2]>, Vec<[u32; 2]>) {
    let (mut sel, mut fic) = (vec![], vec![]);
    for y in 0..g.height() as u32 {
        for x in 0..g.width() as u32 {
            if m.is_fictitious([x, y]) {
                fic.push([x, y]);
            } else if m.is_present([x, y]) {
                sel.push([x, y]);
            }
        }
    }
    (sel, fic)
}

#[test]
fn one_selected_border_point_forces_its_chain_of_fictitious_points() {
    // (3,0) is a B(2) point on the north border: its diamond has one triangle,
    // apex (3,1); (3,1) is needed by one triangle only (apex (2,0)), which is
    // needed by the north B(4) triangle (apex (2,2)), a child of a root.
    let g = five();
    let fa = marks_with(&g, Mode::Fictitious { watertight: false }, &[[3, 0]]);
    let (sel, fic) = present(&fa, &g);
    assert_eq!(sel, vec![[3, 0]]);
    assert_eq!(fic, vec![[2, 0], [3, 1], [2, 2]]);
    assert!(fa.is_selected([3, 0]));
    // (3,1) hangs on the unsplit east triangle's half, (2,2) on the unsplit
    // south-west root; (2,0) is on the border.
    assert_eq!(fa.hanging_vertices(), 2);
    let r = triangulate(&g, &fa, Mode::Fictitious { watertight: false });
    assert_eq!(
        (r.transmitted_points, r.fictitious_points, r.line_triangles),
        (5, 3, 2)
    );
    assert_eq!(r.mesh.triangle_count(), 6);
    let z = |p: [u32; 2]| {
        r.mesh
            .vertices
            .iter()
            .find(|v| [v.col, v.row] == p)
            .unwrap()
            .z_m
    };
    let h = |x: usize, y: usize| g.get(x, y);
    assert_eq!(z([2, 2]), 0.5 * (h(0, 0) + h(4, 4)));
    assert_eq!(z([2, 0]), 0.5 * (h(0, 0) + h(4, 0)));
    assert_eq!(z([3, 1]), 0.5 * (z([2, 2]) + h(4, 0)));
    assert_eq!(z([3, 0]), h(3, 0));
    let opts = CheckOptions::DEFAULT
        .with_conforming(false)
        .with_allow_fictitious(true);
    check_mesh(&g, &r.mesh, &opts).unwrap();
    // Strict: the same mesh is no longer conforming, and without fictitious
    // points allowed its heights are wrong.
    assert!(check_mesh(
        &g,
        &r.mesh,
        &CheckOptions::DEFAULT.with_allow_fictitious(true)
    )
    .is_err());
    assert!(check_mesh(&g, &r.mesh, &CheckOptions::DEFAULT.with_conforming(false)).is_err());

    // Watertight: the east B(4) triangle splits too, through a new fictitious
    // (4,2), so (3,1) no longer hangs; nothing more is transmitted.
    let wt = marks_with(&g, Mode::Fictitious { watertight: true }, &[[3, 0]]);
    let (sel, fic) = present(&wt, &g);
    assert_eq!(sel, vec![[3, 0]]);
    assert_eq!(fic, vec![[2, 0], [3, 1], [2, 2], [4, 2]]);
    let r = triangulate(&g, &wt, Mode::Fictitious { watertight: true });
    assert_eq!(
        (r.transmitted_points, r.fictitious_points, r.line_triangles),
        (5, 4, 0)
    );
    assert_eq!(r.mesh.triangle_count(), 9);
    check_mesh(
        &g,
        &r.mesh,
        &CheckOptions::DEFAULT.with_allow_fictitious(true),
    )
    .unwrap();

    // Conforming: the same triangles, every point real.
    let c = marks_with(&g, Mode::Conforming, &[[3, 0]]);
    let r = triangulate(&g, &c, Mode::Conforming);
    assert_eq!((r.transmitted_points, r.fictitious_points), (9, 0));
    assert_eq!(r.mesh.triangle_count(), 9);
    check_mesh(&g, &r.mesh, &CheckOptions::DEFAULT).unwrap();
}

#[test]
fn selected_depends_on_both_apexes_fictitious_on_one() {
    // (2,1) is a B(2) point with a vertical diagonal (2,0)-(2,2): selected, it
    // needs both apexes (1,1) and (3,1). Each of those is fictitious and needs
    // only the apex of the one triangle that needs it, (2,0) for both; the
    // other apexes of their diamonds, (0,2) and (4,2), stay absent.
    let g = five();
    let fa = marks_with(&g, Mode::Fictitious { watertight: false }, &[[2, 1]]);
    let (sel, fic) = present(&fa, &g);
    assert_eq!(sel, vec![[2, 1]]);
    assert_eq!(fic, vec![[2, 0], [1, 1], [3, 1], [2, 2]]);
    assert!(!fa.is_present([0, 2]) && !fa.is_present([4, 2]));
    let r = triangulate(&g, &fa, Mode::Fictitious { watertight: false });
    let opts = CheckOptions::DEFAULT
        .with_conforming(false)
        .with_allow_fictitious(true);
    check_mesh(&g, &r.mesh, &opts).unwrap();
    // Selecting (1,1) as well makes it depend on both its apexes: (0,2) joins.
    let fa = marks_with(
        &g,
        Mode::Fictitious { watertight: false },
        &[[2, 1], [1, 1]],
    );
    assert!(fa.is_present([0, 2]) && fa.is_fictitious([0, 2]));
    assert!(!fa.is_present([4, 2]));
}

#[test]
fn the_checker_rejects_a_fictitious_height_off_its_diagonal() {
    let g = five();
    let fa = marks_with(&g, Mode::Fictitious { watertight: true }, &[[3, 0]]);
    let mut mesh = triangulate(&g, &fa, Mode::Fictitious { watertight: true }).mesh;
    let opts = CheckOptions::DEFAULT.with_allow_fictitious(true);
    check_mesh(&g, &mesh, &opts).unwrap();
    let k = mesh
        .vertices
        .iter()
        .position(|v| [v.col, v.row] == [3, 1])
        .unwrap();
    mesh.vertices[k].z_m += 0.01;
    let err = check_mesh(&g, &mesh, &opts).unwrap_err();
    assert!(
        matches!(
            err.violations[0],
            Violation::WrongFictitiousHeight { col: 3, row: 1, .. }
        ),
        "{err}"
    );
    // A vertex with an invented height whose diagonal end is missing.
    let c = marks_with(&g, Mode::Conforming, &[[3, 0]]);
    let mut mesh = triangulate(&g, &c, Mode::Conforming).mesh;
    let k = mesh
        .vertices
        .iter()
        .position(|v| [v.col, v.row] == [3, 0])
        .unwrap();
    mesh.vertices[k].z_m += 1.0; // (3,0)'s diagonal ends are (2,0) and (4,0): both there
    let err = check_mesh(&g, &mesh, &opts).unwrap_err();
    assert!(
        matches!(err.violations[0], Violation::WrongFictitiousHeight { .. }),
        "{err}"
    );
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 96, .. proptest::prelude::ProptestConfig::default() })]

    /// Random sizes (2×N, primes, …), rough random heights, every mode: the
    /// strict checker passes with the bound.
    #[test]
    fn random_grids_every_mode_pass_the_strict_checker(
        w in 2usize..48, h in 2usize..48, seed in proptest::prelude::any::<u64>(),
        rough in 0f32..40.0, e in 0f64..15.0,
    ) {
        let heights = cota_fixtures::hills_and_noise(w, h, seed, rough);
        let g = grid(w, h, |x, y| heights[y * w + x]);
        for m in MODES {
            run(&g, e, m);
        }
    }
}

/// Marks of one grid cannot continue the refinement of another: a clear
/// error naming both sizes, where the marks used to be dropped silently.
#[test]
fn marks_of_another_grid_are_refused() {
    use cota_core::refine::{refine_marks, refine_marks_from};
    let g = real();
    let crit = MaxVerticalError { max_error_m: 20.0 };
    let opts = RefineOptions::DEFAULT.with_mode(Mode::Fictitious { watertight: true });
    let (_, marks) = refine_marks(&g, &crit, &opts).unwrap();
    let small = grid(33, 17, |x, y| (x * y) as f32);
    let e = refine_marks_from(&small, &crit, &opts, marks.clone()).unwrap_err();
    assert_eq!(
        e,
        MeshError::MarksSizeMismatch {
            width: 33,
            height: 17,
            marks_width: g.width(),
            marks_height: g.height(),
        }
    );
    assert!(e.to_string().contains("33x17"), "{e}");
    // The same grid continues fine, and only adds points.
    let crit5 = MaxVerticalError { max_error_m: 5.0 };
    let (_, finer) = refine_marks_from(&g, &crit5, &opts, marks.clone()).unwrap();
    assert!(finer.contains(&marks));
    assert!(!marks.contains(&finer));
}
