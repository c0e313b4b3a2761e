//! Golden small cases: exact errors, vertices and triangles on tiny terrains,
//! worked out by hand (see the comments), as martini's test does on its fixture.
#![allow(clippy::unwrap_used, reason = "tests")]

use cota_core::{Bitree, ExtractOptions, GeoRef, HeightGrid, Mesh};

fn run(w: usize, h: usize, heights: Vec<f32>, e: f64) -> (Vec<(u32, u32)>, Vec<[u32; 3]>) {
    let g = HeightGrid::new(w, h, heights, GeoRef::unreferenced(1.0)).unwrap();
    let Mesh {
        vertices,
        triangles,
    } = Bitree::build(&g)
        .unwrap()
        .extract(&ExtractOptions::max_error_m(e))
        .unwrap()
        .mesh;
    (vertices.iter().map(|v| (v.col, v.row)).collect(), triangles)
}

/// 5×5 flat grid with a 4 m bump at (1, 1). The bump is the split point of the
/// 2×2 square at the north-west corner (cut along `\`), so its error 4 m
/// propagates to its parents' split points (2, 0), (0, 2) and the root's (2, 2).
#[test]
fn bump_on_five_by_five() {
    let mut heights = vec![0f32; 25];
    heights[6] = 4.0;
    let g = HeightGrid::new(5, 5, heights.clone(), GeoRef::unreferenced(1.0)).unwrap();
    let errs: Vec<f32> = (0..25)
        .map(|i| Bitree::build(&g).unwrap().error_bound_m(i))
        .collect();
    let mut expected = vec![0f32; 25];
    for i in [2, 6, 10, 12] {
        expected[i] = 4.0;
    }
    assert_eq!(errs, expected);

    let (v, t) = run(5, 5, heights.clone(), 3.9);
    assert_eq!(
        v,
        [
            (0, 0),
            (2, 0),
            (4, 0),
            (1, 1),
            (0, 2),
            (2, 2),
            (0, 4),
            (4, 4)
        ]
    );
    assert_eq!(
        t,
        [
            [5, 2, 1],
            [1, 0, 3],
            [5, 1, 3],
            [7, 2, 5],
            [6, 7, 5],
            [4, 5, 3],
            [0, 4, 3],
            [6, 5, 4]
        ]
    );
    // At 4 m the bump is within tolerance: the two root triangles.
    let (v, t) = run(5, 5, heights, 4.0);
    assert_eq!(v, [(0, 0), (4, 0), (0, 4), (4, 4)]);
    assert_eq!(t, [[0, 3, 1], [3, 0, 2]]);
}

/// 3×2 grid: the padded square is 2×2, so the southern half of the hierarchy
/// is clipped. The north triangle (hypotenuse on row 0, apex (1, 1)) stays whole
/// while the 1 m bump at (1, 0) is tolerated; the west and east halves straddle
/// the border and are always split down to unit triangles.
#[test]
fn clipped_three_by_two() {
    let h = vec![0., 1., 0., 0., 0., 0.];
    let (v, t) = run(3, 2, h.clone(), 10.0);
    assert_eq!(v, [(0, 0), (2, 0), (0, 1), (1, 1), (2, 1)]);
    assert_eq!(t, [[1, 0, 3], [1, 3, 4], [3, 0, 2]]);
    let (v, t) = run(3, 2, h, 0.0);
    assert_eq!(v, [(0, 0), (1, 0), (2, 0), (0, 1), (1, 1), (2, 1)]);
    assert_eq!(t, [[4, 2, 1], [0, 4, 1], [2, 4, 5], [4, 0, 3]]);
}

/// 2×2: one cell, two triangles, whatever the heights.
#[test]
fn single_cell() {
    let (v, t) = run(2, 2, vec![5., -3., 7., 100.], 0.0);
    assert_eq!(v, [(0, 0), (1, 0), (0, 1), (1, 1)]);
    assert_eq!(t.len(), 2);
}
