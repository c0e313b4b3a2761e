//! The checker must fail on each kind of broken mesh: otherwise the tests that
//! rely on it prove nothing.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use cota_core::mesh::check::Violation;
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
