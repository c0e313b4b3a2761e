//! The error of a tile **as the client draws it**: flat triangles between
//! the vertices' Earth-centred (ECEF, WGS 84) positions, measured along the
//! ellipsoid normal against the terrain, folded into the hierarchy's
//! decisions as a proven upper bound per level.
//!
//! Papers `000_ebf7e3a88dffd361.txt` §2–3 (one monotone error per split
//! point, a decision per diamond) and `001_49f2c365e8c41172.txt` (one
//! hierarchy over the mosaic); the drawing rule is the quantized-mesh-1.0
//! specification's (CesiumGS/quantized-mesh): a vertex is placed at its
//! longitude, latitude and height on WGS 84 and the triangles between the
//! vertices are drawn flat. The bitree measures a triangle's error in the
//! lattice's own space, `(λ, φ, h)` with the plane linear in longitude and
//! latitude. This module bounds what drawing it flat in 3D adds.
//!
//! # The bound
//! Let `E(λ, φ, h)` map geodetic coordinates to ECEF. For the geodetic
//! normal `n̂`, `E(λ, φ, h) = E(λ, φ, 0) + h·n̂(λ, φ)` exactly, so a point's
//! height is its distance along the normal. A triangle `T` of the hierarchy
//! has parameter vertices `g_i = (λ_i, φ_i, h_i)`; the lattice's surface is
//! `G(β) = Σ β_i g_i` and the client draws `P(β) = Σ β_i E(g_i)`. With
//! `v_i = g_i − G(β)`, Taylor's theorem at `G(β)` (`Σ β_i v_i = 0`, so the
//! first-order terms cancel) gives
//!
//! `Δ(β) = P(β) − E(G(β)) = ½ Σ β_i D²E[v_i, v_i]` (at points of `T`).
//!
//! The second derivatives of `E` split into an angular part (`E_λλ`, `E_λφ`,
//! `E_φφ`, of size the radius of curvature `r ≤ a²/b + h`) and a height part
//! (`2 dh (E_λh dλ + E_φh dφ)`, where `E_λh = cos φ ê_east` and `E_φh =
//! ê_north` exactly: horizontal unit vectors). With `ρ` the circumradius of
//! `T` in radians (`Σ β_i |v_i|² ≤ ρ²` for a right triangle, its hypotenuse
//! `√2^k` cells of `κ` radians at level `k`, `ρ` half of it) and `span` the
//! spread of its vertex heights:
//!
//! * **vertical**: the normal component of the angular part is at most
//!   `r (cos²φ dλ² + dφ²) ≤ r |v|²`, so `|Δ_v| ≤ V = ½ R ρ²`
//!   (`R = a²/b + max(h, 0)`);
//! * **horizontal**: the angular part's tangential component is at most
//!   `r |sin φ| (cos φ dλ² + 2|dλ dφ|) ≤ 1.7 r |sin φ| |v|²`, and the height
//!   part's is at most `Σ β_i |dh_i| |v_i| ≤ span · 2ρ`, so
//!   `|Δ_h| ≤ H = ½ · 1.7 R sin φ_max ρ² + 2 span ρ`.
//!
//! The drawn point `P(β)` then has a height within `V` of the lattice
//! plane's `H_T(x)` at `x`, the footprint of `G(β)`, and a footprint within
//! `H` (metres on the ground) of `x`. Against the terrain `S` at that
//! footprint `y`: `|h(P) − S(y)| ≤ V + |H_T(x) − H_M(y)| + |H_M(y) − S(y)|`
//! where `H_M` is the lattice mesh's surface (the planes of the leaves). The
//! middle term is at most `s · H` for `s` the steepest plane the segment
//! from `x` to `y` crosses (`T`, or a neighbour within `H` of `T`'s border,
//! whose level differs from `T`'s by at most two in a conforming mesh), and
//! the last is the leaf's own error (`e(T') + ρ_fit`, see
//! [`super::lattice`]). So a leaf of level `k` within `thr − c(k)` of the
//! lattice is within `thr` as drawn, with
//!
//! `c(k) = 1.05 · max_{|k'−k| ≤ 2} (V(k') + s*(k') · H(k'))`,
//!
//! `s*(k')` the steepest plane (metres per ground metre, at the latitude of
//! its vertex farthest from the equator) over the triangles of levels
//! `k' − 2 … k' + 2` near the window ([`LevelStats`], exact maxima over
//! those triangles' vertices), `span(k)` likewise, and a 5 % margin for the
//! second-order terms (the normal turns by `ρ` across `T`; a point moved
//! horizontally by `H` rises by `H²/2r`). `c` is made non-decreasing with
//! the level, so the decision "split `m` iff `e(m) > thr − c(k)`" stays
//! monotone up the tree (errors and `c` both grow towards the root) and
//! both triangles of a diamond still decide alike: conforming, no
//! T-junction.
//!
//! Beyond the window the terrain is the ellipsoid (`h = 0`, no slope): only
//! `V` remains ([`DrawnBound::slack_m`] with `inside = false`). Whether a
//! split point is inside depends on it and its level alone ([`is_inside`]),
//! the parents of an inside point are inside, and the inside bound is the
//! larger, so monotony holds across the window's border too.
//!
//! Coarse tiles get the triangles they need to follow the globe: a zoom-0
//! tile's triangles split until `V < e_0` (hypotenuses of about 18°, some
//! 500 triangles per root tile), and finer zooms need fewer (`V` falls with
//! the square of the size, `e_z` only linearly).
//!
//! # Runtime
//! [`level_stats`]: every triangle of every level over the region, `O(n)`
//! in all (`1.5 n` triangles at the finest levels), in parallel.

use rayon::prelude::*;

use super::scheme::GeographicScheme;
use crate::bitree::error_code::SplitRule;
use crate::hierarchy::Tri;

/// WGS 84 semi-major axis, metres.
const A_M: f64 = 6_378_137.0;
/// WGS 84 semi-minor axis, metres.
const B_M: f64 = 6_356_752.314_245_179;
/// Levels kept: `k` up to `2·30 + 1`.
pub const LEVELS: usize = 64;

/// The level of a triangle: `2·log2(s)` for the `B(s)` triangles (the
/// hypotenuse a side of an `s`-square), `2·log2(s) + 1` for `A(s)` (the
/// hypotenuse its diagonal); the hypotenuse is `√2^k` cells.
#[inline]
pub fn level_key(t: &Tri) -> usize {
    let dx = t.a[0].abs_diff(t.b[0]);
    let dy = t.a[1].abs_diff(t.b[1]);
    if dx == 0 || dy == 0 {
        2 * dx.max(dy).trailing_zeros() as usize
    } else {
        2 * dx.trailing_zeros() as usize + 1
    }
}

/// Per level ([`level_key`]), over the level's triangles near the window:
/// the steepest plane (metres per metre of ground) and the largest spread of
/// vertex heights (metres). Maxima, so parts merge into the whole exactly.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LevelStats {
    /// Steepest plane per level, metres per metre.
    pub slope: Vec<f64>,
    /// Largest vertex-height spread per level, metres.
    pub span_m: Vec<f64>,
}

impl LevelStats {
    /// Both together: the maxima per level.
    pub fn merge(&self, other: &LevelStats) -> LevelStats {
        let max = |a: &[f64], b: &[f64]| -> Vec<f64> {
            (0..a.len().max(b.len()))
                .map(|i| {
                    let x = a.get(i).copied().unwrap_or(0.0);
                    let y = b.get(i).copied().unwrap_or(0.0);
                    x.max(y)
                })
                .collect()
        };
        LevelStats {
            slope: max(&self.slope, &other.slope),
            span_m: max(&self.span_m, &other.span_m),
        }
    }

    fn at(v: &[f64], k: usize) -> f64 {
        v.get(k).copied().unwrap_or(0.0)
    }
}

/// The stats of the triangles of the squares of side `s` (powers of two in
/// `sizes`, inclusive) whose squares `[i·s, (i+1)·s] × [j·s, (j+1)·s]` lie
/// in `region` (global lattice `[x0, y0, x1, y1]`, inclusive), heights from
/// `height` (global lattice position).
pub fn level_stats(
    scheme: &GeographicScheme,
    region: [u64; 4],
    sizes: [u64; 2],
    height: &(impl Fn(u64, u64) -> f32 + Sync),
) -> LevelStats {
    let mut out = LevelStats {
        slope: vec![0.0; LEVELS],
        span_m: vec![0.0; LEVELS],
    };
    // The finest squares (side 2) are bounded from the lattice's steps
    // instead ([`DrawnBound::new`]): they are most of the triangles and the
    // smallest terms.
    let mut s = sizes[0].max(4).next_power_of_two();
    while s <= sizes[1] {
        let (i0, i1) = (region[0].div_ceil(s), (region[2] + 1) / s);
        let (j0, j1) = (region[1].div_ceil(s), (region[3] + 1) / s);
        if i0 < i1 && j0 < j1 {
            let [a, b] = squares_stats(scheme, [i0, j0, i1, j1], s, height);
            let (ka, kb) = (
                2 * s.trailing_zeros() as usize + 1,
                2 * s.trailing_zeros() as usize,
            );
            out.slope[ka] = a[0];
            out.span_m[ka] = a[1];
            out.slope[kb] = b[0];
            out.span_m[kb] = b[1];
        }
        s *= 2;
    }
    out
}

/// Over squares `i0..i1 × j0..j1` of side `s`: `[slope, span]` of the
/// halves (`A(s)`) and of the side triangles (`B(s)`). Slopes use the
/// metres of a cell at the square row's edge farthest from the equator.
fn squares_stats(
    scheme: &GeographicScheme,
    [i0, j0, i1, j1]: [u64; 4],
    s: u64,
    height: &(impl Fn(u64, u64) -> f32 + Sync),
) -> [[f64; 2]; 2] {
    let both = |a: [[f64; 2]; 2], b: [[f64; 2]; 2]| {
        [0, 1].map(|k| [a[k][0].max(b[k][0]), a[k][1].max(b[k][1])])
    };
    (j0..j1)
        .into_par_iter()
        .map(|j| {
            let lat = [j * s, (j + 1) * s]
                .map(|y| scheme.lat_of(y as f64).abs())
                .into_iter()
                .fold(0.0, f64::max);
            let m = metres_per_cell(scheme, lat);
            let mut acc = [[0.0; 2]; 2];
            for i in i0..i1 {
                let (sides, halves) = super::cap::square_tris(i, j, s);
                for t in halves {
                    acc[0] = max2(acc[0], tri_stats(m, &t, height));
                }
                for t in sides {
                    acc[1] = max2(acc[1], tri_stats(m, &t, height));
                }
            }
            acc
        })
        .reduce(|| [[0.0; 2]; 2], both)
}

fn max2(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0].max(b[0]), a[1].max(b[1])]
}

/// `[slope, span]` of one triangle: its plane's gradient in metres per
/// metre (`[ex, ey]`: metres per cell east and north), and its vertex
/// heights' spread.
#[inline]
fn tri_stats([ex, ey]: [f64; 2], t: &Tri, height: &(impl Fn(u64, u64) -> f32 + Sync)) -> [f64; 2] {
    let p = [t.a, t.b, t.c].map(|q| {
        let (x, y) = (u64::from(q[0]), u64::from(q[1]));
        [x as f64, y as f64, f64::from(height(x, y))]
    });
    let lo = p[0][2].min(p[1][2]).min(p[2][2]);
    let hi = p[0][2].max(p[1][2]).max(p[2][2]);
    if hi == lo {
        return [0.0, 0.0];
    }
    let (u, v) = (sub(p[1], p[0]), sub(p[2], p[0]));
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let (gx, gy) = (n[0] / (n[2] * ex), n[1] / (n[2] * ey));
    [(gx * gx + gy * gy).sqrt(), hi - lo]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Metres per lattice cell east and north at latitude `lat_deg` (WGS 84).
fn metres_per_cell(scheme: &GeographicScheme, lat_deg: f64) -> [f64; 2] {
    let [mx, my] = crate::grid::metres_per_degree(lat_deg);
    let d = scheme.cell_deg();
    // A cell at the pole has no width: keep the slope finite.
    [(mx * d).max(1e-3 * my * d), my * d]
}

/// `levels` with the squares of side 2 (`B(2)`, `A(2)`) bounded from the
/// lattice's steps: a plane's gradient is at most `G` per cell along each
/// axis, and its vertices, two cells apart at most along each axis, differ
/// by at most `2G`.
fn finest_from_steps(levels: &LevelStats, [ex, ey]: [f64; 2], g: f64) -> LevelStats {
    let mut out = levels.merge(&LevelStats {
        slope: vec![0.0; 4],
        span_m: vec![0.0; 4],
    });
    let slope = g * (1.0 / (ex * ex) + 1.0 / (ey * ey)).sqrt();
    for k in [2, 3] {
        out.slope[k] = out.slope[k].max(slope);
        out.span_m[k] = out.span_m[k].max(2.0 * g);
    }
    out
}

/// The slack `c(k)` per level inside and outside the window (see the module
/// docs), and the fitted lattice's residual against the source.
#[derive(Debug, Clone, PartialEq)]
pub struct DrawnBound {
    inside_m: Vec<f64>,
    outside_m: Vec<f64>,
}

impl DrawnBound {
    /// The bound for a lattice of `scheme` over `window`, whose heights lie
    /// in `lo_m..=hi_m` with steps of at most `max_step_m` (`G` of
    /// [`super::plan`]), with per-level `levels`.
    pub fn new(
        scheme: &GeographicScheme,
        window: [u64; 4],
        [lo_m, hi_m, max_step_m]: [f64; 3],
        levels: &LevelStats,
    ) -> DrawnBound {
        let kappa = scheme.cell_deg().to_radians();
        let r_in = A_M * A_M / B_M + hi_m.max(0.0);
        let r_out = A_M * A_M / B_M;
        let lat_max = [window[1], window[3]]
            .map(|y| scheme.lat_of(y as f64).abs())
            .into_iter()
            .fold(0.0, f64::max)
            .min(90.0);
        let _ = lo_m;
        let k_h = 1.7 * r_in * lat_max.to_radians().sin();
        let levels = &finest_from_steps(levels, metres_per_cell(scheme, lat_max), max_step_m);
        let rho = |k: usize| 2f64.sqrt().powi(k as i32) * kappa / 2.0;
        let slope_near = |k: usize| {
            (k.saturating_sub(2)..=k + 2)
                .map(|j| LevelStats::at(&levels.slope, j))
                .fold(0.0, f64::max)
        };
        let raw: Vec<f64> = (0..LEVELS)
            .map(|k| {
                let r = rho(k);
                let v = 0.5 * r_in * r * r;
                let h = 0.5 * k_h * r * r + 2.0 * LevelStats::at(&levels.span_m, k) * r;
                v + slope_near(k) * h
            })
            .collect();
        let mut inside_m: Vec<f64> = (0..LEVELS)
            .map(|k| {
                1.05 * (k.saturating_sub(2)..=(k + 2).min(LEVELS - 1))
                    .map(|j| raw[j])
                    .fold(0.0, f64::max)
            })
            .collect();
        let mut outside_m: Vec<f64> = (0..LEVELS)
            .map(|k| 1.05 * 0.5 * r_out * rho(k) * rho(k))
            .collect();
        for k in 1..LEVELS {
            inside_m[k] = inside_m[k].max(inside_m[k - 1]);
            outside_m[k] = outside_m[k].max(outside_m[k - 1]).min(inside_m[k]);
        }
        DrawnBound {
            inside_m,
            outside_m,
        }
    }

    /// What a split point of level `k` must leave below its zoom's threshold
    /// for the drawn triangle: `c(k)` inside the window, `c(k)` of the
    /// ellipsoid alone beyond it. (The source's own residuals are left per
    /// split point, see [`super::fit`].)
    pub fn slack_m(&self, k: usize, inside: bool) -> f64 {
        let k = k.min(LEVELS - 1);
        if inside {
            self.inside_m[k]
        } else {
            self.outside_m[k]
        }
    }

    /// The largest slack a leaf at the finest level keeps (unit triangles
    /// cannot split): what the maximum zoom's bound must exceed.
    pub fn finest_slack_m(&self) -> f64 {
        self.slack_m(1, true)
    }

    /// The rules of a zoom of threshold `threshold_m`, per level and side.
    /// Each threshold is rounded down to an error-code value
    /// ([`crate::bitree::error_code`]), so a split point's 16-bit code alone
    /// decides it exactly (no tie-break), in one process or merged from
    /// shards' codes.
    pub fn rules(&self, threshold_m: f64) -> ZoomRules {
        let rule = |slack: f64| {
            let t = threshold_m - slack;
            if t < 0.0 {
                LevelRule::Always
            } else {
                LevelRule::Above(SplitRule::at_code(SplitRule::new(t).floor))
            }
        };
        ZoomRules {
            levels: (0..LEVELS)
                .map(|k| [rule(self.slack_m(k, false)), rule(self.slack_m(k, true))])
                .collect(),
        }
    }
}

/// How a level decides at one zoom.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LevelRule {
    /// Always split: the drawn triangle alone exceeds the bound.
    Always,
    /// Split when the lattice error exceeds this rule's threshold.
    Above(SplitRule),
}

/// One zoom's rules per level, `[outside, inside]` the window.
#[derive(Debug, Clone, PartialEq)]
pub struct ZoomRules {
    levels: Vec<[LevelRule; 2]>,
}

impl ZoomRules {
    /// The smallest floor code of the zoom's rules (`u16::MAX` when every
    /// level always splits): a source error whose code is at most this
    /// decides nothing ([`super::relevant`]).
    pub fn min_floor(&self) -> u16 {
        self.levels
            .iter()
            .flatten()
            .filter_map(|r| match r {
                LevelRule::Always => None,
                LevelRule::Above(rule) => Some(rule.floor),
            })
            .min()
            .unwrap_or(u16::MAX)
    }

    /// The rule of triangle `t` (`window`: the lattice's, inclusive).
    #[inline]
    pub fn of(&self, t: &Tri, window: [u64; 4]) -> LevelRule {
        self.levels[level_key(t).min(LEVELS - 1)][usize::from(is_inside(t, window))]
    }
}

/// Whether the split point of `t` is *inside*: the square around it of
/// half-side `g` meets `window`, with `g = 2s` for a `B(s)` triangle and
/// `g = 3s` for an `A(s)` one. It depends on the split point and the level
/// alone, so both triangles of a diamond agree; it holds the diamond (whose
/// vertices lie within `s` of its split point); and it holds the children's
/// squares (a child's split point lies within `s/2` of its parent's: from
/// `B(s)` to `A(s)`, `s/2 + 2s ≤ 3s`; from `A(s)` to `B(2s)`,
/// `s/2 + 3s ≤ 4s`), so the parents of an inside point are inside.
#[inline]
pub fn is_inside(t: &Tri, window: [u64; 4]) -> bool {
    let (dx, dy) = (t.a[0].abs_diff(t.b[0]), t.a[1].abs_diff(t.b[1]));
    let s = u64::from(dx.max(dy));
    let g = if dx == 0 || dy == 0 { 2 * s } else { 3 * s };
    let m = t.mid();
    let (x, y) = (u64::from(m[0]), u64::from(m[1]));
    x.saturating_sub(g) <= window[2]
        && x + g >= window[0]
        && y.saturating_sub(g) <= window[3]
        && y + g >= window[1]
}

#[cfg(test)]
mod test {
    use super::*;

    fn ecef(lon: f64, lat: f64, h: f64) -> [f64; 3] {
        let (l, p) = (lon.to_radians(), lat.to_radians());
        let e2 = 1.0 - B_M * B_M / (A_M * A_M);
        let n = A_M / (1.0 - e2 * p.sin() * p.sin()).sqrt();
        [
            (n + h) * p.cos() * l.cos(),
            (n + h) * p.cos() * l.sin(),
            (n * (1.0 - e2) + h) * p.sin(),
        ]
    }

    /// Geodetic height of an ECEF point (Bowring, iterated).
    fn height_of(p: [f64; 3]) -> (f64, f64, f64) {
        let e2 = 1.0 - B_M * B_M / (A_M * A_M);
        let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
        let lon = p[1].atan2(p[0]);
        let mut lat = p[2].atan2(r * (1.0 - e2));
        let mut h = 0.0;
        for _ in 0..8 {
            let n = A_M / (1.0 - e2 * lat.sin() * lat.sin()).sqrt();
            h = r / lat.cos() - n;
            lat = p[2].atan2(r * (1.0 - e2 * n / (n + h)));
        }
        (lon.to_degrees(), lat.to_degrees(), h)
    }

    #[test]
    fn level_keys() {
        let b2 = Tri {
            a: [0, 0],
            b: [2, 0],
            c: [1, 1],
        };
        let a2 = Tri {
            a: [0, 0],
            b: [2, 2],
            c: [2, 0],
        };
        let unit = Tri {
            a: [0, 0],
            b: [1, 1],
            c: [1, 0],
        };
        assert_eq!(
            (level_key(&b2), level_key(&a2), level_key(&unit)),
            (2, 3, 1)
        );
    }

    /// The flat triangle between three points on a sloping plane, at every
    /// latitude and at sizes from a cell to a hemisphere: the drawn height
    /// at random points (compared with the lattice plane at the drawn
    /// footprint) stays within the bound of the triangle's level.
    #[test]
    fn the_bound_holds_for_drawn_triangles() {
        let scheme = GeographicScheme {
            max_zoom: 12,
            tile_cells: 64,
            from_greenwich: false,
        };
        let d = scheme.cell_deg();
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for k in [3usize, 5, 9, 15, 21, 27, 33] {
            let s = 1u64 << (k / 2);
            for _ in 0..40 {
                let lat0 = -80.0 + 150.0 * rnd();
                let lon0 = -170.0 + 300.0 * rnd();
                let (y0, x0) = (((90.0 - lat0) / d) as u64, ((lon0 + 180.0) / d) as u64);
                let (x0, y0) = ((x0 / s) * s, (y0 / s) * s);
                let g = 2000.0 / s as f64;
                let (gx, gy, base) = (g * (2.0 * rnd() - 1.0), g * (2.0 * rnd() - 1.0), 500.0);
                let h = |x: u64, y: u64| {
                    (base + gx * (x as f64 - x0 as f64) + gy * (y as f64 - y0 as f64)) as f32
                };
                let region = [x0, y0, x0 + s, y0 + s];
                let t = super::super::cap::square_tris(x0 / s, y0 / s, s).1[0];
                let stats = level_stats(&scheme, region, [s, s], &h);
                let lo_hi = [-2000.0, 4000.0, 2.0 * g];
                let b = DrawnBound::new(&scheme, region, lo_hi, &stats);
                let c = b.slack_m(level_key(&t), true);
                let g = [t.a, t.b, t.c].map(|q| {
                    let (x, y) = (u64::from(q[0]), u64::from(q[1]));
                    [
                        scheme.lon_of(x as f64),
                        scheme.lat_of(y as f64),
                        f64::from(h(x, y)),
                    ]
                });
                let p = g.map(|q| ecef(q[0], q[1], q[2]));
                for _ in 0..50 {
                    let (u, v) = (rnd(), rnd());
                    let (u, v) = if u + v > 1.0 {
                        (1.0 - u, 1.0 - v)
                    } else {
                        (u, v)
                    };
                    let w = [1.0 - u - v, u, v];
                    let q = [0, 1, 2].map(|c| w[0] * p[0][c] + w[1] * p[1][c] + w[2] * p[2][c]);
                    let (lon, lat, hd) = height_of(q);
                    let (x, y) = ((lon + 180.0) / d, (90.0 - lat) / d);
                    let plane = base + gx * (x - x0 as f64) + gy * (y - y0 as f64);
                    assert!(
                        (hd - plane).abs() <= c,
                        "k {k} at {lat0:.1}: drawn {hd} plane {plane} bound {c}"
                    );
                }
            }
        }
    }

    #[test]
    fn coarse_levels_always_split_fine_ones_barely_change() {
        let scheme = GeographicScheme {
            max_zoom: 12,
            tile_cells: 64,
            from_greenwich: false,
        };
        let b = DrawnBound::new(
            &scheme,
            [0, 0, 10, 10],
            [0.0, 0.0, 0.0],
            &LevelStats::default(),
        );
        // A root tile's halves (k = 37) sag by thousands of kilometres.
        assert!(b.slack_m(37, false) > 1e6);
        // A zoom-12 tile's cells: well under a millimetre.
        assert!(b.slack_m(3, false) < 1e-3);
        let r = b.rules(77_000.0);
        let root = Tri {
            a: [0, 0],
            b: [1 << 18, 1 << 18],
            c: [1 << 18, 0],
        };
        assert_eq!(r.of(&root, [0, 0, 10, 10]), LevelRule::Always);
    }
}
