//! The checker must fail on each kind of broken mesh: otherwise the tests that
//! rely on it prove nothing.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use cota_core::mesh::check::Violation;
use cota_core::tin::{self, TinOptions};
use cota_core::{check_mesh, Bitree, CheckOptions, ExtractOptions, GeoRef, HeightGrid, Mesh};

fn setup() -> (HeightGrid, Mesh) {
    let (w, h) = (33, 33);
    let v = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            20.0 * (x * 0.3).sin() + 10.0 * (y * 0.25).cos()
        })
        .collect();
    let g = HeightGrid::new(w, h, v, GeoRef::unreferenced(1.0)).unwrap();
    let mesh = Bitree::build(&g)
        .unwrap()
        .extract(&ExtractOptions::max_error_m(2.0))
        .unwrap()
        .mesh;
    (g, mesh)
}

fn first(g: &HeightGrid, m: &Mesh, o: CheckOptions) -> Violation {
    check_mesh(g, m, &o).unwrap_err().violations[0].clone()
}

#[test]
fn passes_when_intact() {
    let (g, m) = setup();
    let r = check_mesh(&g, &m, &CheckOptions::conforming(2.0)).unwrap();
    assert!(r.metrics.max_error_m <= 2.0 && r.metrics.max_error_m > 0.5);
    assert_eq!(r.metrics.samples, 33 * 33);
}

#[test]
fn catches_a_missing_triangle() {
    let (g, mut m) = setup();
    m.triangles.remove(m.triangles.len() / 2);
    assert!(matches!(
        first(&g, &m, CheckOptions::DEFAULT),
        Violation::OpenEdge { .. }
    ));
}

#[test]
fn catches_a_flipped_triangle() {
    let (g, mut m) = setup();
    m.triangles[3].swap(0, 1);
    assert!(matches!(
        first(&g, &m, CheckOptions::DEFAULT),
        Violation::Flipped { .. }
    ));
}

#[test]
fn catches_a_wrong_height_and_a_tight_bound() {
    let (g, mut m) = setup();
    let r = check_mesh(&g, &m, &CheckOptions::conforming(0.1));
    assert!(matches!(
        r.unwrap_err().violations[0],
        Violation::ErrorBound { .. }
    ));
    m.vertices[5].z_m += 0.25;
    assert!(matches!(
        first(&g, &m, CheckOptions::DEFAULT),
        Violation::WrongHeight { .. }
    ));
}

#[test]
fn catches_a_t_junction() {
    // Split one triangle at its hypotenuse midpoint without splitting the
    // neighbour: conforming check must see the open edge.
    let (g, mut m) = setup();
    let p = |m: &Mesh, i: u32| (m.vertices[i as usize].col, m.vertices[i as usize].row);
    // The first triangle whose hypotenuse midpoint is a sample but not a vertex.
    let (ti, a, b, c, mid) = (0..m.triangles.len())
        .find_map(|ti| {
            let t = m.triangles[ti];
            let e = (0..3).max_by_key(|&e| {
                let (a, b) = (p(&m, t[e]), p(&m, t[(e + 1) % 3]));
                (a.0 as i64 - b.0 as i64).pow(2) + (a.1 as i64 - b.1 as i64).pow(2)
            })?;
            let (a, b, c) = (t[e], t[(e + 1) % 3], t[(e + 2) % 3]);
            let (pa, pb) = (p(&m, a), p(&m, b));
            if (pa.0 + pb.0) % 2 != 0 || (pa.1 + pb.1) % 2 != 0 {
                return None;
            }
            let mid = ((pa.0 + pb.0) / 2, (pa.1 + pb.1) / 2);
            let taken = m.vertices.iter().any(|v| (v.col, v.row) == mid);
            (!taken).then_some((ti, a, b, c, mid))
        })
        .expect("a mesh at 2 m has unsplit triangles");
    m.vertices.push(cota_core::MeshVertex {
        col: mid.0,
        row: mid.1,
        z_m: g.get(mid.0 as usize, mid.1 as usize),
    });
    let k = (m.vertices.len() - 1) as u32;
    m.triangles[ti] = [a, k, c];
    m.triangles.push([k, b, c]);
    let v = first(&g, &m, CheckOptions::DEFAULT);
    assert!(matches!(v, Violation::OpenEdge { .. }), "{v:?}");
    // Without the conformity requirement, the same mesh passes.
    check_mesh(&g, &m, &CheckOptions::DEFAULT.with_conforming(false)).unwrap();
}

#[test]
fn catches_overlap_and_out_of_range() {
    let (g, mut m) = setup();
    let t = m.triangles[7];
    m.triangles.push(t);
    assert!(matches!(
        first(&g, &m, CheckOptions::DEFAULT),
        Violation::EdgeOveruse { .. }
    ));
    let (g, mut m) = setup();
    m.triangles[0][1] = 1_000_000;
    assert!(matches!(
        first(&g, &m, CheckOptions::DEFAULT),
        Violation::IndexOutOfRange { .. }
    ));
}

#[test]
fn height_tolerance_allows_moved_heights_up_to_it() {
    let (g, mut m) = setup();
    m.vertices[5].z_m += 0.25;
    let strict = CheckOptions::conforming(2.5);
    assert!(matches!(
        first(&g, &m, strict),
        Violation::WrongHeight { .. }
    ));
    assert!(check_mesh(&g, &m, &strict.with_height_tolerance_m(0.25)).is_ok());
    assert!(check_mesh(&g, &m, &strict.with_height_tolerance_m(0.125)).is_err());
}

/// A TIN of the test grid at 2 m, and one of its interior edges with a
/// sample strictly inside that is not a vertex: (triangle, corner of the
/// edge's start, the sample).
fn tin_setup() -> (HeightGrid, Mesh, usize, usize, (u32, u32)) {
    let (g, _) = setup();
    let m = tin::build(&g, &TinOptions::max_error_m(2.0)).unwrap().mesh;
    let p = |i: u32| (m.vertices[i as usize].col, m.vertices[i as usize].row);
    let border = |a: (u32, u32), b: (u32, u32)| {
        (a.0 == b.0 && (a.0 == 0 || a.0 == 32)) || (a.1 == b.1 && (a.1 == 0 || a.1 == 32))
    };
    let (ti, e, s) = (0..m.triangles.len())
        .find_map(|ti| {
            let t = m.triangles[ti];
            (0..3).find_map(|e| {
                let (a, b) = (p(t[e]), p(t[(e + 1) % 3]));
                let (dx, dy) = (b.0 as i64 - a.0 as i64, b.1 as i64 - a.1 as i64);
                let g = (1..=dx.abs().max(dy.abs()))
                    .rev()
                    .find(|&k| dx % k == 0 && dy % k == 0)?;
                let s = ((a.0 as i64 + dx / g) as u32, (a.1 as i64 + dy / g) as u32);
                (g > 1 && !border(a, b) && !m.vertices.iter().any(|v| (v.col, v.row) == s))
                    .then_some((ti, e, s))
            })
        })
        .expect("a TIN at 2 m has a long interior edge");
    (g, m, ti, e, s)
}

fn add_vertex(g: &HeightGrid, m: &mut Mesh, s: (u32, u32)) -> u32 {
    m.vertices.push(cota_core::MeshVertex {
        col: s.0,
        row: s.1,
        z_m: g.get(s.0 as usize, s.1 as usize),
    });
    (m.vertices.len() - 1) as u32
}

#[test]
fn a_tin_passes_the_general_tests() {
    let (g, m, ..) = tin_setup();
    let r = check_mesh(&g, &m, &CheckOptions::tin(2.0)).unwrap();
    assert!(r.metrics.max_error_m <= 2.0 && r.metrics.max_error_m > 1.0);
}

#[test]
fn catches_a_t_junction_in_a_tin() {
    // Split one side of an interior edge at a sample on it.
    let (g, mut m, ti, e, s) = tin_setup();
    let t = m.triangles[ti];
    let (a, b, c) = (t[e], t[(e + 1) % 3], t[(e + 2) % 3]);
    let k = add_vertex(&g, &mut m, s);
    m.triangles[ti] = [a, k, c];
    m.triangles.push([k, b, c]);
    let v = first(&g, &m, CheckOptions::tin(2.0));
    assert!(matches!(v, Violation::OpenEdge { .. }), "{v:?}");
    // The direct test names the T-junction itself.
    let all = check_mesh(&g, &m, &CheckOptions::tin(2.0).with_conforming(false)).unwrap_err();
    assert!(
        all.violations.iter().any(|v| matches!(
            v,
            Violation::VertexOnEdge { col, row, .. } if (*col, *row) == s
        )),
        "{all}"
    );
}

#[test]
fn catches_an_unused_vertex_on_an_edge() {
    // A vertex inside an edge that no triangle uses: the tiling checks
    // cannot see it, the general tests must.
    let (g, mut m, _, _, s) = tin_setup();
    add_vertex(&g, &mut m, s);
    check_mesh(&g, &m, &CheckOptions::conforming(2.0)).unwrap();
    let all = check_mesh(&g, &m, &CheckOptions::tin(2.0)).unwrap_err();
    assert!(all
        .violations
        .iter()
        .any(|v| matches!(v, Violation::VertexOnEdge { .. })));
    assert!(all
        .violations
        .iter()
        .any(|v| matches!(v, Violation::UnusedVertex { .. })));
}

#[test]
fn catches_an_error_violation_in_a_tin() {
    let (g, m, _, _, s) = tin_setup();
    // A tighter bound than the TIN was made for.
    assert!(matches!(
        first(&g, &m, CheckOptions::tin(1.0)),
        Violation::ErrorBound { .. }
    ));
    // A sample that is not a vertex moved by 3 m.
    let mut v = g.heights().to_vec();
    v[s.1 as usize * 33 + s.0 as usize] += 3.0;
    let g2 = HeightGrid::new(33, 33, v, GeoRef::unreferenced(1.0)).unwrap();
    let bad = first(&g2, &m, CheckOptions::tin(2.0));
    assert!(
        matches!(bad, Violation::ErrorBound { col, row, .. } if (col, row) == s),
        "{bad:?}"
    );
}
