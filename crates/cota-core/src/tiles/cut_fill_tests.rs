//! Fill tiles ([`Prepared::fills`]): every tile with a child gets all four,
//! the quadrants beyond the data cut from the same hierarchy, on the
//! ellipsoid, as coarsely as the drawn bound allows.

use std::collections::HashSet;

use super::*;
use crate::tiles::lattice::LatticeOptions;
use crate::{Crs, GeoRef, PixelIs};

/// A 1°×1° geographic grid at 0.01°, relief of a few hundred metres.
fn source() -> HeightGrid {
    let n = 101;
    let heights = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f32, (i / n) as f32);
            300.0 + 80.0 * (x * 0.11).sin() + 60.0 * (y * 0.07).cos()
        })
        .collect();
    let georef = GeoRef {
        crs: Crs::WGS84,
        origin_x: 10.3,
        origin_y: 1.4,
        pixel_x: 0.01,
        pixel_y: -0.01,
        pixel_is: PixelIs::Point,
        known: true,
    };
    HeightGrid::new(n, n, heights, georef).unwrap()
}

#[test]
fn fills_give_every_refined_tile_four_children_on_the_ellipsoid() {
    let g = source();
    let lattice = Lattice::resample(&g, &LatticeOptions::DEFAULT.with_max_zoom(Some(9))).unwrap();
    let prep = Prepared::new(&lattice, &g, &TilerOptions::DEFAULT).unwrap();
    let made: HashSet<TileId> = prep.tiles().collect();
    let fills: Vec<TileId> = prep.fills().collect();
    assert!(!fills.is_empty());
    let all: HashSet<TileId> = made.iter().chain(&fills).copied().collect();
    assert_eq!(all.len(), made.len() + fills.len(), "a fill is also made");
    for t in &all {
        let n = quadrants(*t).iter().filter(|c| all.contains(c)).count();
        assert!(n == 0 || n == 4, "{t}: {n} children");
    }
    let w = lattice.window();
    let mut beyond_window = 0;
    for &f in &fills {
        assert!(
            prep.cut(f, false, false).is_err(),
            "{f} cut as a pyramid tile"
        );
        assert!(
            quadrants(f).iter().all(|c| !all.contains(c)),
            "{f} has children"
        );
        let m = prep.cut_fill(f, true).unwrap();
        assert!(m.children.is_empty());
        let [x, y] = lattice.scheme().tile_origin(f);
        let beyond = x > w[2] || x + m.cells < w[0] || y > w[3] || y + m.cells < w[1];
        if !beyond {
            continue;
        }
        beyond_window += 1;
        // Beyond the window: 0 m, straight up, and the leaves the drawn
        // bound's curvature term alone makes.
        assert!(m.mesh.vertices.iter().all(|v| v.z_m == 0.0), "{f}");
        assert!(m.normals_enu.unwrap().iter().all(|n| *n == UP), "{f}");
        let zi = prep.zoom_index(f.z).unwrap();
        let always = walk_leaves([x, y], m.cells, |t| {
            prep.rules[zi].of(t, w) == LevelRule::Always
        });
        assert_eq!(m.mesh.triangle_count(), always.len(), "{f}");
    }
    assert!(beyond_window > 0);
    let data = made.iter().find(|t| t.z > 0).unwrap();
    assert!(prep.cut_fill(*data, false).is_err());
    assert!(!prep.is_fill(TileId { z: 0, x: 1, y: 0 }));
}
