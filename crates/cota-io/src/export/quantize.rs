//! The plan of a quantized GLB (`KHR_mesh_quantization`): how the mesh is cut
//! into primitives, and the integer grid each primitive's positions sit on.
//!
//! # Positions
//! Every vertex sits on a grid sample, so its horizontal position is an exact
//! integer: within a primitive, `X = |col − c₀|·Kx` and `Y = |row − r₀|·Ky`
//! (16-bit, `c₀`, `r₀` the primitive's corner that makes them non-negative,
//! `Kx`, `Ky` = ⌊65 535 / span⌋ the largest integers that keep them 16-bit).
//! The primitive's node maps them back: `x = x(c₀) + X·|aₓ|/Kx`, where
//! `x = aₓ·col + bₓ` is the output frame ([`Coords`](super::Coords)), likewise
//! for y. The multipliers `K` make the horizontal unit small, so that rule
//! (3) below costs little height precision (see Normals).
//!
//! Heights are quantized once for the whole mesh, on a step `s` that is a
//! power of two: `q = round((z − t)/s)`, 16-bit, with `t` a multiple of `s`,
//! and every node decodes `z' = t + q·s`. So a vertex shared by two
//! primitives has the same height in both (no crack), `|z' − z| ≤ s/2`, and
//! `z'` is exact in `f32` as in `f64` (a 16-bit integer times a power of two,
//! plus a multiple of it below 2²⁴ steps). `s` is the smallest power of two
//! with (1) the height range in at most 65 533 steps, (2) every height
//! within 2²² steps of zero (the `f32` exactness), (3) `s ≥ u·g/`[`MAX_ANISOTROPY`]
//! for every primitive, `u` its coarser horizontal unit and `g` its steepest
//! vertex slope (the normal's horizontal over vertical part), taken at most 1.
//!
//! # Error
//! Linear interpolation moves the surface by at most the largest move of its
//! corners, so the written mesh's error at any sample is at most the mesh's
//! own plus `s/2` ([`GlbQuantization::z_step_m`]). The written heights are
//! given by [`GlbQuantization::written_heights`], for the invariant checker.
//!
//! # Normals
//! A node's scale is not uniform, and a viewer maps a normal by the inverse
//! transpose of the node's matrix: so the normal stored is `S·n`
//! renormalised (`S` the node's scale, `n` the vertex normal in the output
//! frame), as a normalised signed byte triple. Of the eight roundings of
//! `127·S·n`, the one whose decoded direction `S⁻¹·c` is closest to `n` is
//! kept, among those the Khronos validator takes for unit length. A rounding
//! error of 1/254 in a stored component changes the decoded slope `g` by a
//! relative `max(1, g·u/s)/254` or so (`u` the horizontal unit, `s` the
//! vertical one): rule (3) keeps `g·u/s` at most [`MAX_ANISOTROPY`] for slopes
//! up to 45° (a few percent, about 2° of direction at worst), and flat parts
//! (the sea) put no limit on `s`. Measured on the bundled tile at 5 m: 0.07°
//! mean and 0.7° worst from the float layout's normals.
//!
//! # Primitives
//! The triangles are binned by the square tile of side `T` samples their
//! centroid falls in (`T` chosen for about 32 768 vertices a tile, at least
//! 128), tiles in row-major order, triangles in mesh order within a tile
//! (a parallel counting sort). A tile is cut into runs of at most
//! [`TRIANGLES_PER_PART`] triangles, and a run with more than 65 535 vertices
//! (16-bit indices, 65 535 being the primitive restart value) or a span
//! above 65 535 samples is halved until it fits. A primitive's vertices are found with a bitset over its range of
//! vertex numbers and numbered in that (row-major) order; indices are their
//! ranks. Vertices on the border between tiles are written once per tile (a
//! few percent). Compact tiles keep the horizontal units small (rule 3).

use std::ops::Range;

use cota_core::{HeightGrid, Mesh};
use rayon::prelude::*;

use super::coords::Frame;
use super::error::ExportError;
use super::geometry::{check_mesh, vertex_normals};
use super::options::ExportOptions;
use super::par::on_pool;

/// Most triangles in one primitive (before any halving).
pub(crate) const TRIANGLES_PER_PART: usize = 1 << 16;

/// Most vertices in one primitive: 16-bit indices, 65 535 excluded (the
/// primitive restart value).
pub(crate) const MAX_PART_VERTICES: usize = 65_535;

/// Largest 16-bit coordinate.
const MAX_U16: u64 = 65_535;

/// Most height steps used (of the 65 535 a u16 holds: one for the rounding
/// of the lowest height down to a multiple of the step, one spare).
const HEIGHT_STEPS: f64 = 65_533.0;

/// Largest product of a primitive's horizontal-to-vertical unit ratio and
/// its steepest slope (at most 1) (see the module doc, Normals): with 8-bit
/// normals the decoded direction's error is then about 2° at a 45° slope.
pub(crate) const MAX_ANISOTROPY: f64 = 16.0;

/// Vertices aimed at per tile.
const TILE_VERTICES: f64 = 32_768.0;

/// Smallest tile side, samples.
const MIN_TILE: u32 = 128;

/// One primitive: a run of triangles and its own vertices.
#[derive(Debug, Clone)]
pub(crate) struct Part {
    /// How many triangles it holds.
    pub triangles: usize,
    /// Its vertices (mesh indices), in increasing order.
    pub vertices: Vec<u32>,
    /// Three local indices per triangle, in the frame's winding.
    pub indices: Vec<u16>,
    /// The column and row that map to X = 0 and Y = 0.
    pub origin: [u32; 2],
    /// Stored units per column and per row.
    pub k: [u32; 2],
    /// Whether X grows with the column (else against it), and Y with the row.
    pub ascending: [bool; 2],
    /// Its steepest vertex slope, at most 1.
    pub slope: f64,
}

/// How a mesh is written as a quantized GLB (see the module doc): its
/// primitives and its height step.
///
/// Make one with [`GlbQuantization::new`], ask it what it will write
/// ([`z_step_m`](Self::z_step_m), [`written_heights`](Self::written_heights)),
/// then write with [`write_glb_quantized`](super::write_glb_quantized), or let
/// [`write_glb`](super::write_glb) make it with
/// [`ExportOptions::quantize`](super::ExportOptions::quantize).
#[derive(Debug, Clone)]
pub struct GlbQuantization {
    pub(crate) parts: Vec<Part>,
    /// The height step `s`, metres (a power of two).
    pub(crate) z_step_m: f64,
    /// The height of q = 0, metres (a multiple of the step).
    pub(crate) z_base_m: f64,
    /// The output frame's axes (see [`Frame::axes`]).
    pub(crate) axes: ([f64; 2], [f64; 2]),
    /// The unit vertex normals in the output frame.
    pub(crate) normals: Vec<[f32; 3]>,
}

impl GlbQuantization {
    /// Plans the quantized GLB of `mesh` over `grid` in `opts.coords` (see
    /// [`ExportOptions::quantize`]; `opts.quantize` itself is not read).
    ///
    /// # Errors
    /// The mesh checks of [`ExportError`]; [`ExportError::TooLarge`] for a
    /// triangle spanning more than 65 535 columns or rows.
    pub fn new(mesh: &Mesh, grid: &HeightGrid, opts: &ExportOptions) -> Result<Self, ExportError> {
        on_pool(|| {
            check_mesh(mesh)?;
            GlbQuantization::plan(mesh, &Frame::new(grid, opts.coords))
        })
    }

    /// Plans the quantized GLB of `mesh` in `frame`. The mesh must have been
    /// checked (indices in range, finite heights, a triangle at least).
    pub(crate) fn plan(mesh: &Mesh, frame: &Frame) -> Result<Self, ExportError> {
        let (order, tiles) = spatial_order(mesh);
        let runs: Vec<&[u32]> = tiles
            .iter()
            .flat_map(|r| order[r.clone()].chunks(TRIANGLES_PER_PART))
            .collect();
        let normals = vertex_normals(mesh, frame);
        let parts: Vec<Vec<Part>> = runs
            .into_par_iter()
            .map(|r| parts_of(mesh, frame, &normals, r))
            .collect::<Result<_, _>>()?;
        let parts: Vec<Part> = parts.into_iter().flatten().collect();
        let axes = frame.axes();
        let sloped_unit = parts
            .iter()
            .map(|p| {
                let u =
                    (axes.0[0].abs() / f64::from(p.k[0])).max(axes.1[0].abs() / f64::from(p.k[1]));
                u * p.slope
            })
            .fold(0.0, f64::max);
        let (lo, hi) = height_range(mesh);
        let z_step_m = height_step(hi - lo, lo.abs().max(hi.abs()), sloped_unit);
        Ok(GlbQuantization {
            parts,
            z_step_m,
            z_base_m: (lo / z_step_m).floor() * z_step_m,
            axes,
            normals,
        })
    }

    /// The height step, metres: a power of two. Every written height is
    /// within half of it of the mesh's height, so the written mesh's error at
    /// any sample is at most the mesh's own plus `z_step_m() / 2`.
    pub fn z_step_m(&self) -> f64 {
        self.z_step_m
    }

    /// The number of glTF primitives (and nodes) written.
    pub fn primitives(&self) -> usize {
        self.parts.len()
    }

    /// The vertices written, counting those on the border of two primitives
    /// once per primitive.
    pub fn written_vertices(&self) -> usize {
        self.parts.iter().map(|p| p.vertices.len()).sum()
    }

    /// The height the file gives each vertex of `mesh` (the mesh this
    /// quantization was made for), metres: `t + q·s`, exact in `f32`. Swap
    /// them into the mesh to measure or check what is written.
    pub fn written_heights(&self, mesh: &Mesh) -> Vec<f32> {
        mesh.vertices
            .par_iter()
            .map(|v| self.dequantize(self.quantize(v.z_m)))
            .collect()
    }

    /// The 16-bit height code of `z_m`.
    #[inline]
    pub(crate) fn quantize(&self, z_m: f32) -> u16 {
        // In range by the choice of the step and base (module doc).
        ((f64::from(z_m) - self.z_base_m) / self.z_step_m)
            .round()
            .clamp(0.0, MAX_U16 as f64) as u16
    }

    /// The height of code `q`, metres (exact).
    #[inline]
    pub(crate) fn dequantize(&self, q: u16) -> f32 {
        (self.z_base_m + f64::from(q) * self.z_step_m) as f32
    }
}

/// The lowest and highest vertex heights.
fn height_range(mesh: &Mesh) -> (f64, f64) {
    let (lo, hi) = mesh
        .vertices
        .par_iter()
        .fold(
            || (f32::INFINITY, f32::NEG_INFINITY),
            |(lo, hi), v| (lo.min(v.z_m), hi.max(v.z_m)),
        )
        .reduce(
            || (f32::INFINITY, f32::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    (f64::from(lo), f64::from(hi))
}

/// The smallest power of two meeting the rules of the module doc for a
/// height range `range_m`, heights up to `magnitude_m` and a largest
/// horizontal unit times slope `unit`.
fn height_step(range_m: f64, magnitude_m: f64, unit: f64) -> f64 {
    let need = (range_m / HEIGHT_STEPS)
        .max(magnitude_m / f64::from(1u32 << 22))
        .max(unit / MAX_ANISOTROPY)
        .max(f64::MIN_POSITIVE);
    let mut step = 2f64.powi(need.log2().floor() as i32);
    while step < need {
        step *= 2.0;
    }
    step
}

/// The triangles binned by tile (see the module doc, Primitives): the
/// triangle numbers in tile order, and each tile's range of them.
fn spatial_order(mesh: &Mesh) -> (Vec<u32>, Vec<Range<usize>>) {
    let (w, h) = mesh
        .vertices
        .par_iter()
        .fold(|| (0, 0), |(w, h), v| (w.max(v.col), h.max(v.row)))
        .reduce(|| (0, 0), |a, b| (a.0.max(b.0), a.1.max(b.1)));
    let (w, h) = (u64::from(w) + 1, u64::from(h) + 1);
    let density = mesh.vertices.len() as f64 / (w * h) as f64;
    let side = ((TILE_VERTICES / density).sqrt() as u64).max(u64::from(MIN_TILE));
    let across = w.div_ceil(side);
    let tiles = (across * h.div_ceil(side)) as usize;
    let tile_of = |t: [u32; 3]| {
        let v = t.map(|i| mesh.vertices[i as usize]);
        let col = (u64::from(v[0].col) + u64::from(v[1].col) + u64::from(v[2].col)) / 3;
        let row = (u64::from(v[0].row) + u64::from(v[1].row) + u64::from(v[2].row)) / 3;
        ((row / side) * across + col / side) as usize
    };
    // Counts per chunk of triangles and tile, then each chunk scatters its
    // triangles from its own offsets: a stable counting sort in parallel.
    let chunks: Vec<&[[u32; 3]]> = mesh.triangles.chunks(TRIANGLES_PER_PART).collect();
    let counts: Vec<Vec<usize>> = chunks
        .par_iter()
        .map(|c| {
            let mut n = vec![0; tiles];
            c.iter().for_each(|&t| n[tile_of(t)] += 1);
            n
        })
        .collect();
    let mut starts = vec![vec![0; tiles]; chunks.len()];
    let mut ranges = Vec::with_capacity(tiles);
    let mut at = 0;
    for tile in 0..tiles {
        let first = at;
        for (c, n) in counts.iter().enumerate() {
            starts[c][tile] = at;
            at += n[tile];
        }
        ranges.push(first..at);
    }
    let order: Vec<std::sync::atomic::AtomicU32> = (0..mesh.triangles.len())
        .map(|_| Default::default())
        .collect();
    chunks
        .par_iter()
        .zip(starts.par_iter_mut())
        .enumerate()
        .for_each(|(c, (chunk, next))| {
            for (k, &t) in chunk.iter().enumerate() {
                let tile = tile_of(t);
                let id = (c * TRIANGLES_PER_PART + k) as u32;
                order[next[tile]].store(id, std::sync::atomic::Ordering::Relaxed);
                next[tile] += 1;
            }
        });
    let order = order.into_iter().map(|a| a.into_inner()).collect();
    ranges.retain(|r| !r.is_empty());
    (order, ranges)
}

/// The parts of the triangle run `run`: one, or the parts of its halves when
/// it has too many vertices or spans too far.
fn parts_of(
    mesh: &Mesh,
    frame: &Frame,
    normals: &[[f32; 3]],
    run: &[u32],
) -> Result<Vec<Part>, ExportError> {
    match part(mesh, frame, normals, run)? {
        Some(p) => Ok(vec![p]),
        None => {
            let (a, b) = run.split_at(run.len() / 2);
            let mut a = parts_of(mesh, frame, normals, a)?;
            a.extend(parts_of(mesh, frame, normals, b)?);
            Ok(a)
        }
    }
}

/// The part of the triangle run `run`, `None` when it must be halved.
///
/// # Errors
/// [`ExportError::TooLarge`] for a single triangle spanning more than 65 535
/// columns or rows.
fn part(
    mesh: &Mesh,
    frame: &Frame,
    normals: &[[f32; 3]],
    run: &[u32],
) -> Result<Option<Part>, ExportError> {
    let corners = || run.iter().flat_map(|&t| mesh.triangles[t as usize]);
    let lo = corners().min().unwrap_or(0);
    let hi = corners().max().unwrap_or(0);
    let words = ((hi - lo) as usize >> 6) + 1;
    let mut bits = vec![0u64; words];
    for i in corners() {
        let k = (i - lo) as usize;
        bits[k >> 6] |= 1 << (k & 63);
    }
    let mut rank = Vec::with_capacity(words);
    let mut vertices = Vec::new();
    for (w, &word) in bits.iter().enumerate() {
        rank.push(vertices.len() as u32);
        let mut b = word;
        while b != 0 {
            vertices.push(lo + (w as u32) * 64 + b.trailing_zeros());
            b &= b - 1;
        }
    }
    if vertices.len() > MAX_PART_VERTICES {
        return Ok(None);
    }
    let Some((origin, k, ascending)) = placement(mesh, frame, &vertices, run.len())? else {
        return Ok(None);
    };
    let local = |i: u32| {
        let k = (i - lo) as usize;
        let below = bits[k >> 6] & ((1u64 << (k & 63)) - 1);
        (rank[k >> 6] + below.count_ones()) as u16
    };
    let indices = run
        .iter()
        .flat_map(|&t| frame.orient(mesh.triangles[t as usize]).map(local))
        .collect();
    let slope = vertices
        .iter()
        .map(|&i| slope(normals[i as usize]))
        .fold(0.0, f64::max);
    Ok(Some(Part {
        triangles: run.len(),
        vertices,
        indices,
        origin,
        k,
        ascending,
        slope,
    }))
}

/// The slope of a surface of unit normal `n` (horizontal over vertical
/// part), at most 1.
fn slope(n: [f32; 3]) -> f64 {
    let [x, y, z] = n.map(f64::from);
    let h = (x * x + y * y).sqrt();
    if h >= z.abs() {
        1.0
    } else {
        h / z.abs()
    }
}

/// Where a part's X and Y start and how fine they are: `None` when its span
/// needs the part halved.
#[allow(clippy::type_complexity, reason = "a private triple")]
fn placement(
    mesh: &Mesh,
    frame: &Frame,
    vertices: &[u32],
    triangles: usize,
) -> Result<Option<([u32; 2], [u32; 2], [bool; 2])>, ExportError> {
    let (mut c, mut r) = ([u32::MAX, 0], [u32::MAX, 0]);
    for &i in vertices {
        let v = mesh.vertices[i as usize];
        c = [c[0].min(v.col), c[1].max(v.col)];
        r = [r[0].min(v.row), r[1].max(v.row)];
    }
    let span = u64::from((c[1] - c[0]).max(r[1] - r[0]));
    if span > MAX_U16 {
        if triangles > 1 {
            return Ok(None);
        }
        return Err(ExportError::TooLarge {
            what: "columns or rows spanned by one triangle in 16-bit positions",
            count: span,
            max: MAX_U16,
        });
    }
    let (ax, ay) = frame.axes();
    let ascending = [ax[0] > 0.0, ay[0] > 0.0];
    let origin = [
        if ascending[0] { c[0] } else { c[1] },
        if ascending[1] { r[0] } else { r[1] },
    ];
    let k = [c[1] - c[0], r[1] - r[0]].map(|s| (MAX_U16 / u64::from(s.max(1))) as u32);
    Ok(Some((origin, k, ascending)))
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn steps_are_the_smallest_power_of_two_that_fits() {
        // Range rule: 1000 m in 65 533 steps needs 0.01526 m -> 2^-6.
        assert_eq!(height_step(1000.0, 1000.0, 0.0), 2f64.powi(-6));
        // Anisotropy rule: a 1 m unit needs 1/16 m.
        assert_eq!(height_step(10.0, 10.0, 1.0), 0.0625);
        // Exactly a power of two stays.
        assert_eq!(height_step(HEIGHT_STEPS * 0.5, 1.0, 0.0), 0.5);
        // A flat mesh high up: the f32 rule.
        let s = height_step(0.0, 4000.0, 0.0);
        assert!(s >= 4000.0 / f64::from(1u32 << 22) && s < 2.0 * 4000.0 / f64::from(1u32 << 22));
    }
}
