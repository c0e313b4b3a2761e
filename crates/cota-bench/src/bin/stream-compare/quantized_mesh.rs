//! A minimal Cesium quantized-mesh-1.0 encoder, written from the public
//! specification (github.com/CesiumGS/quantized-mesh), to size cota's
//! progressive stream against the format terrain servers ship.
//!
//! 1. **Header** (88 bytes): tile centre (3 × f64, ECEF), minimum and maximum
//!    height (2 × f32), bounding sphere (4 × f64), horizon occlusion point
//!    (3 × f64). Their values do not change the size; we fill them from the
//!    grid's georeference roughly (a sphere, not WGS 84), as a server would.
//! 2. **Vertices**: `vertexCount: u32`, then the `u`, `v`, `height` arrays of
//!    `u16` in 0..=32767 (u west→east, v south→north, height min→max), each
//!    delta-coded against the previous vertex and zig-zag encoded. Vertices
//!    are renumbered in order of first use by the triangles, as encoders do
//!    so that the index codes stay small.
//! 3. **Indices**: padding to 2 (16-bit) or 4 (32-bit, above 65 536 vertices)
//!    bytes, `triangleCount: u32`, then the indices high-water-mark coded
//!    (`code = highest − index`, `highest` grows by one at each new vertex),
//!    triangles counter-clockwise.
//! 4. **Edge indices**: west, south, east, north lists (`u32` count and
//!    16- or 32-bit indices) of the vertices on each side of the tile.
//! 5. No extensions (no normals, no water mask). Servers gzip tiles; we report
//!    the gzip size at flate2's best level.

use cota_core::{HeightGrid, Mesh};

fn zigzag(d: i32) -> u16 {
    ((d << 1) ^ (d >> 31)) as u16
}

/// The quantized-mesh-1.0 bytes of `mesh` over `grid` (uncompressed).
pub fn encode(mesh: &Mesh, grid: &HeightGrid) -> Vec<u8> {
    let (w, h) = (grid.width() as f64 - 1.0, grid.height() as f64 - 1.0);
    // Renumber vertices by first use.
    let mut new_of = vec![u32::MAX; mesh.vertices.len()];
    let mut order = Vec::with_capacity(mesh.vertices.len());
    for t in &mesh.triangles {
        for &i in t {
            if new_of[i as usize] == u32::MAX {
                new_of[i as usize] = order.len() as u32;
                order.push(i);
            }
        }
    }
    let (zmin, zmax) = mesh
        .vertices
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), v| {
            (a.min(v.z_m), b.max(v.z_m))
        });
    let zspan = (zmax - zmin).max(1e-6) as f64;
    let mut out = Vec::new();
    // Header: an Earth-centred sphere approximation of the tile.
    let g = grid.georef();
    let (lon, lat) = g.sample_xy(w / 2.0, h / 2.0);
    let r = 6_371_000.0 + (zmin as f64 + zmax as f64) / 2.0;
    let (lo, la) = (lon.to_radians(), lat.to_radians());
    let c = [
        r * la.cos() * lo.cos(),
        r * la.cos() * lo.sin(),
        r * la.sin(),
    ];
    for v in c {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&zmin.to_le_bytes());
    out.extend_from_slice(&zmax.to_le_bytes());
    for v in c {
        out.extend_from_slice(&v.to_le_bytes());
    }
    let [dx, dy] = grid.cell_size_m();
    out.extend_from_slice(&(0.5 * (w * dx).hypot(h * dy)).to_le_bytes());
    for v in c {
        out.extend_from_slice(&(v / 6_371_000.0).to_le_bytes());
    }
    // Vertex data.
    let n = order.len();
    out.extend_from_slice(&(n as u32).to_le_bytes());
    let quant = |i: u32| {
        let v = mesh.vertices[i as usize];
        let u = (v.col as f64 / w * 32767.0).round() as i32;
        let vv = ((h - v.row as f64) / h * 32767.0).round() as i32;
        let z = (((v.z_m - zmin) as f64) / zspan * 32767.0).round() as i32;
        [u, vv, z]
    };
    let q: Vec<[i32; 3]> = order.iter().map(|&i| quant(i)).collect();
    for k in 0..3 {
        let mut prev = 0;
        for p in &q {
            out.extend_from_slice(&zigzag(p[k] - prev).to_le_bytes());
            prev = p[k];
        }
    }
    // Index data.
    let wide = n > 65_536;
    let align = if wide { 4 } else { 2 };
    while out.len() % align != 0 {
        out.push(0);
    }
    out.extend_from_slice(&(mesh.triangles.len() as u32).to_le_bytes());
    let put = |out: &mut Vec<u8>, x: u32| {
        if wide {
            out.extend_from_slice(&x.to_le_bytes());
        } else {
            out.extend_from_slice(&(x as u16).to_le_bytes());
        }
    };
    let mut highest = 0u32;
    for t in &mesh.triangles {
        for &i in t {
            let j = new_of[i as usize];
            put(&mut out, highest - j);
            if j == highest {
                highest += 1;
            }
        }
    }
    // Edge indices: west, south, east, north.
    // (coordinate, value): west u = 0, south v = 0, east u = max, north v = max.
    let sides = [(0, 0), (1, 0), (0, 32767), (1, 32767)];
    for (k, value) in sides {
        let list: Vec<u32> = (0..n as u32)
            .filter(|&i| q[i as usize][k] == value)
            .collect();
        out.extend_from_slice(&(list.len() as u32).to_le_bytes());
        for i in list {
            put(&mut out, i);
        }
    }
    out
}
