//! The check of a decoded tile **as a client draws it**, against the
//! source the user gave: independent of the tiler's own error model
//! ([`cota_core::tiles::drawn`]), it places the decoded vertices on WGS 84
//! in Earth-centred coordinates (ECEF), takes the flat triangles between
//! them, and measures heights along the ellipsoid normal.
//!
//! References: the quantized-mesh-1.0 specification (CesiumGS/quantized-mesh:
//! `u`, `v`, heights and the tile's rectangle give each vertex's longitude,
//! latitude and height; the client draws the triangles between the
//! vertices' ECEF positions) and the WGS 84 ellipsoid ([`super::ellipsoid`]).
//!
//! Two measures:
//! 1. **At every source sample** ([`check_samples`]): the normal through the
//!    sample's position on the ellipsoid meets the drawn surface at a height
//!    (found exactly: the ray against the planes of the triangle over the
//!    sample and, near an edge, of its neighbours); its difference from the
//!    sample's height is what the zoom's bound promises.
//! 2. **At random points of the drawn triangles** ([`check_random`]): a
//!    point of a flat ECEF triangle taken back to geodetic coordinates,
//!    compared with the source's bilinear surface where there is data (a
//!    deviation between samples, reported) and with the ellipsoid far from
//!    the data (where the bound holds).
//!
//! Across the antimeridian ([`Against::across_antimeridian`]) every
//! longitude is also looked for a turn east and west (`±360°`): a tile
//! west of 180° W is measured against the samples of a source that gives
//! them as 180.1°, and the other way round.

use cota_core::{GeoTransform, HeightGrid, PixelIs};

use super::decode::DecodedTile;
use super::ellipsoid::{ecef, enu_axes, geodetic};

/// One input DEM: its samples and the map from its CRS to WGS 84.
#[derive(Debug, Clone, Copy)]
pub struct SourceGrid<'a> {
    /// The samples (no voids where checked: voids are skipped).
    pub grid: &'a HeightGrid,
    /// Its CRS to WGS 84 longitude/latitude.
    pub transform: &'a dyn GeoTransform,
}

/// A sample of a source: WGS 84 longitude, latitude (degrees), height (m).
pub type Sample = [f64; 3];

/// The sources' samples, found by longitude/latitude rectangle.
#[derive(Debug)]
pub struct SourceSamples<'a> {
    sources: Vec<Located<'a>>,
    /// Samples are looked for a turn east and west too.
    wrap: bool,
}

/// The turns (degrees of longitude) at which a point is looked for: none,
/// or also one east and one west.
fn turns(wrap: bool) -> &'static [f64] {
    if wrap {
        &[0.0, 360.0, -360.0]
    } else {
        &[0.0]
    }
}

/// A source with, when its CRS is not WGS 84 geographic, its samples'
/// longitudes and latitudes in buckets of a coarse grid.
#[derive(Debug)]
struct Located<'a> {
    src: SourceGrid<'a>,
    buckets: Option<Buckets>,
}

/// Samples (`[lon, lat, h]`) in a `n × n` grid of buckets over `rect`.
#[derive(Debug)]
struct Buckets {
    rect: [f64; 4],
    n: usize,
    starts: Vec<usize>,
    samples: Vec<Sample>,
}

impl<'a> SourceSamples<'a> {
    /// The samples of `sources` (voids skipped).
    pub fn new(sources: &[SourceGrid<'a>]) -> SourceSamples<'a> {
        SourceSamples::with_wrap(sources, false)
    }

    /// The samples of `sources`, looked for a turn east and west too when
    /// `wrap` (data across the antimeridian).
    pub fn with_wrap(sources: &[SourceGrid<'a>], wrap: bool) -> SourceSamples<'a> {
        let sources = sources
            .iter()
            .map(|&src| Located {
                src,
                buckets: (!src.transform.is_identity()).then(|| Buckets::of(src, wrap)),
            })
            .collect();
        SourceSamples { sources, wrap }
    }

    /// Calls `f` with every sample inside `[west, south, east, north]`
    /// (closed), degrees (its longitude brought into the rectangle's turn).
    pub fn for_each_in(&self, rect: [f64; 4], f: &mut impl FnMut(Sample)) {
        for &k in turns(self.wrap) {
            let q = [rect[0] + k, rect[1], rect[2] + k, rect[3]];
            let g = &mut |s: Sample| f([s[0] - k, s[1], s[2]]);
            for s in &self.sources {
                match &s.buckets {
                    None => affine_samples(s.src.grid, q, g),
                    Some(b) => b.for_each_in(q, g),
                }
            }
        }
    }
}

/// The samples of a WGS 84 geographic grid inside `rect`, by its affine
/// transform.
fn affine_samples(grid: &HeightGrid, rect: [f64; 4], f: &mut impl FnMut(Sample)) {
    let g = grid.georef();
    let half = match g.pixel_is {
        PixelIs::Area => 0.5,
        PixelIs::Point => 0.0,
    };
    let (w, h) = (grid.width() as f64, grid.height() as f64);
    let range = |a: f64, b: f64, o: f64, p: f64, n: f64| {
        let (i, j) = ((a - o) / p - half, (b - o) / p - half);
        let (lo, hi) = (i.min(j), i.max(j));
        let lo = (lo - 1e-9).ceil().max(0.0);
        let hi = (hi + 1e-9).floor().min(n - 1.0);
        (lo <= hi).then_some((lo as usize, hi as usize))
    };
    let (Some((c0, c1)), Some((r0, r1))) = (
        range(rect[0], rect[2], g.origin_x, g.pixel_x, w),
        range(rect[1], rect[3], g.origin_y, g.pixel_y, h),
    ) else {
        return;
    };
    for r in r0..=r1 {
        for c in c0..=c1 {
            let z = grid.get(c, r);
            if z.is_nan() {
                continue;
            }
            let (lon, lat) = g.sample_xy(c as f64, r as f64);
            if lon >= rect[0] && lon <= rect[2] && lat >= rect[1] && lat <= rect[3] {
                f([lon, lat, f64::from(z)]);
            }
        }
    }
}

impl Buckets {
    const N: usize = 256;

    /// The samples of `src`, longitudes modulo 360° when `wrap` (so that
    /// data across the antimeridian stay together).
    fn of(src: SourceGrid<'_>, wrap: bool) -> Buckets {
        let g = src.grid.georef();
        let mut all = Vec::with_capacity(src.grid.len());
        for r in 0..src.grid.height() {
            for c in 0..src.grid.width() {
                let z = src.grid.get(c, r);
                let (x, y) = g.sample_xy(c as f64, r as f64);
                if let (false, Some([lon, lat])) = (z.is_nan(), src.transform.to_lonlat(x, y)) {
                    let lon = if wrap { lon.rem_euclid(360.0) } else { lon };
                    all.push([lon, lat, f64::from(z)]);
                }
            }
        }
        let mut rect = [f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY];
        for s in &all {
            rect = [
                rect[0].min(s[0]),
                rect[1].min(s[1]),
                rect[2].max(s[0]),
                rect[3].max(s[1]),
            ];
        }
        let n = Self::N;
        let cell = |s: &Sample| Self::cell_of(rect, n, s[0], s[1]);
        let mut counts = vec![0usize; n * n + 1];
        for s in &all {
            counts[cell(s) + 1] += 1;
        }
        for i in 1..counts.len() {
            counts[i] += counts[i - 1];
        }
        let mut fill = counts.clone();
        let mut samples = vec![[0.0; 3]; all.len()];
        for s in all {
            let k = cell(&s);
            samples[fill[k]] = s;
            fill[k] += 1;
        }
        Buckets {
            rect,
            n,
            starts: counts,
            samples,
        }
    }

    fn cell_of(rect: [f64; 4], n: usize, lon: f64, lat: f64) -> usize {
        let fx = ((lon - rect[0]) / (rect[2] - rect[0]).max(1e-12) * n as f64) as isize;
        let fy = ((lat - rect[1]) / (rect[3] - rect[1]).max(1e-12) * n as f64) as isize;
        let c = |v: isize| v.clamp(0, n as isize - 1) as usize;
        c(fy) * n + c(fx)
    }

    fn for_each_in(&self, q: [f64; 4], f: &mut impl FnMut(Sample)) {
        if self.samples.is_empty()
            || q[2] < self.rect[0]
            || q[0] > self.rect[2]
            || q[3] < self.rect[1]
            || q[1] > self.rect[3]
        {
            return;
        }
        let n = self.n;
        let lo = Self::cell_of(self.rect, n, q[0], q[1]);
        let hi = Self::cell_of(self.rect, n, q[2], q[3]);
        let (i0, j0, i1, j1) = (lo % n, lo / n, hi % n, hi / n);
        for j in j0..=j1 {
            for i in i0..=i1 {
                let k = j * n + i;
                for s in &self.samples[self.starts[k]..self.starts[k + 1]] {
                    if s[0] >= q[0] && s[0] <= q[2] && s[1] >= q[1] && s[1] <= q[3] {
                        f(*s);
                    }
                }
            }
        }
    }
}

/// A decoded tile placed on the Earth.
#[derive(Debug)]
pub struct DrawnTile<'t> {
    tile: &'t DecodedTile,
    /// Per vertex: longitude, latitude, height.
    geo: Vec<[f64; 3]>,
    /// Per vertex: ECEF position.
    xyz: Vec<[f64; 3]>,
    /// Triangles around each vertex (CSR).
    fan_starts: Vec<usize>,
    fans: Vec<u32>,
}

impl<'t> DrawnTile<'t> {
    /// `tile` over `rect` (`[west, south, east, north]`, degrees).
    pub fn new(tile: &'t DecodedTile, rect: [f64; 4]) -> DrawnTile<'t> {
        let geo: Vec<[f64; 3]> = (0..tile.u.len()).map(|i| tile.geodetic(i, rect)).collect();
        let xyz = geo.iter().map(|g| ecef(g[0], g[1], g[2])).collect();
        let n = geo.len();
        let mut fan_starts = vec![0usize; n + 1];
        for t in &tile.triangles {
            for &v in t {
                fan_starts[v as usize + 1] += 1;
            }
        }
        for i in 1..=n {
            fan_starts[i] += fan_starts[i - 1];
        }
        let mut fill = fan_starts.clone();
        let mut fans = vec![0u32; fan_starts[n]];
        for (k, t) in tile.triangles.iter().enumerate() {
            for &v in t {
                fans[fill[v as usize]] = k as u32;
                fill[v as usize] += 1;
            }
        }
        DrawnTile {
            tile,
            geo,
            xyz,
            fan_starts,
            fans,
        }
    }

    /// The same tile drawn from other ECEF positions of its vertices (the
    /// float32 positions of its 3D Tiles GLB): footprints stay the tile's,
    /// heights are measured on `xyz` (positions beyond the tile's vertex
    /// count are ignored; missing ones keep the tile's own).
    pub fn with_positions(mut self, xyz: &[[f64; 3]]) -> DrawnTile<'t> {
        for (p, q) in self.xyz.iter_mut().zip(xyz) {
            *p = *q;
        }
        self
    }

    /// The drawn surface's height along the normal at `(lon, lat)`, found
    /// from triangle `k` (whose footprint holds the point) or, when the
    /// normal meets the surface beside it, from a triangle sharing a vertex
    /// with it; `None` when no triangle of the tile is met (the surface
    /// there belongs to the neighbouring tile).
    pub fn height_at(&self, k: usize, lon: f64, lat: f64) -> Option<f64> {
        let o = ecef(lon, lat, 0.0);
        let up = enu_axes(lon, lat)[2];
        if let Some(h) = self.hit(k, o, up) {
            return Some(h);
        }
        for &v in &self.tile.triangles[k] {
            let (a, b) = (self.fan_starts[v as usize], self.fan_starts[v as usize + 1]);
            for &j in &self.fans[a..b] {
                if let Some(h) = self.hit(j as usize, o, up) {
                    return Some(h);
                }
            }
        }
        None
    }

    /// Where the ray `o + t·up` meets triangle `k`, as `t`, if it does.
    fn hit(&self, k: usize, o: [f64; 3], up: [f64; 3]) -> Option<f64> {
        let [a, b, c] = self.tile.triangles[k].map(|i| self.xyz[i as usize]);
        let (e1, e2) = (sub(b, a), sub(c, a));
        let n = cross(e1, e2);
        let denom = dot(n, up);
        if denom.abs() < 1e-12 * dot(n, n).sqrt() {
            return None;
        }
        let t = dot(n, sub(a, o)) / denom;
        let q = [o[0] + t * up[0], o[1] + t * up[1], o[2] + t * up[2]];
        let nn = dot(n, n);
        let w1 = dot(cross(sub(q, a), e2), n) / nn;
        let w2 = dot(cross(e1, sub(q, a)), n) / nn;
        let eps = -1e-9;
        (w1 >= eps && w2 >= eps && 1.0 - w1 - w2 >= eps).then_some(t)
    }

    /// Triangle `k`'s footprint: vertex longitudes and latitudes.
    fn footprint(&self, k: usize) -> [[f64; 2]; 3] {
        self.tile.triangles[k].map(|i| {
            let g = self.geo[i as usize];
            [g[0], g[1]]
        })
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Whether `p` lies in the triangle `f` (closed, with a relative slack).
fn in_footprint(f: &[[f64; 2]; 3], p: [f64; 2]) -> bool {
    let d = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let area = d(f[0], f[1], f[2]);
    let slack = -1e-12 * area.abs();
    let (s0, s1, s2) = (d(f[0], f[1], p), d(f[1], f[2], p), d(f[2], f[0], p));
    if area >= 0.0 {
        s0 >= slack && s1 >= slack && s2 >= slack
    } else {
        s0 <= -slack && s1 <= -slack && s2 <= -slack
    }
}

/// What [`check_samples`] found.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SampleCheck {
    /// Source samples measured.
    pub samples: u64,
    /// The largest |drawn − source|, metres.
    pub max_error_m: f64,
    /// Where: longitude, latitude.
    pub at: [f64; 2],
    /// Samples whose normal meets the surface only in a neighbouring tile
    /// (measured on their triangle's plane, extended).
    pub beside: u64,
}

impl SampleCheck {
    /// Both together.
    pub fn merge(self, o: SampleCheck) -> SampleCheck {
        let (max_error_m, at) = if o.max_error_m > self.max_error_m {
            (o.max_error_m, o.at)
        } else {
            (self.max_error_m, self.at)
        };
        SampleCheck {
            samples: self.samples + o.samples,
            max_error_m,
            at,
            beside: self.beside + o.beside,
        }
    }
}

/// The drawn tile against every source sample in its footprint: the
/// height along the normal where the drawn surface is met.
pub fn check_samples(tile: &DrawnTile<'_>, samples: &SourceSamples<'_>) -> SampleCheck {
    let mut out = SampleCheck::default();
    for k in 0..tile.tile.triangles.len() {
        let f = tile.footprint(k);
        let rect = [
            f[0][0].min(f[1][0]).min(f[2][0]),
            f[0][1].min(f[1][1]).min(f[2][1]),
            f[0][0].max(f[1][0]).max(f[2][0]),
            f[0][1].max(f[1][1]).max(f[2][1]),
        ];
        samples.for_each_in(rect, &mut |[lon, lat, h]| {
            if !in_footprint(&f, [lon, lat]) {
                return;
            }
            let drawn = tile.height_at(k, lon, lat).unwrap_or_else(|| {
                out.beside += 1;
                tile.plane_height(k, lon, lat)
            });
            let e = (drawn - h).abs();
            out.samples += 1;
            if e > out.max_error_m {
                out.max_error_m = e;
                out.at = [lon, lat];
            }
        });
    }
    out
}

impl DrawnTile<'_> {
    /// The height where the normal at `(lon, lat)` meets the plane of
    /// triangle `k` (extended).
    fn plane_height(&self, k: usize, lon: f64, lat: f64) -> f64 {
        let o = ecef(lon, lat, 0.0);
        let up = enu_axes(lon, lat)[2];
        let [a, b, c] = self.tile.triangles[k].map(|i| self.xyz[i as usize]);
        let n = cross(sub(b, a), sub(c, a));
        dot(n, sub(a, o)) / dot(n, up)
    }
}

/// What the reference surface is at a point: a height (the source's
/// bilinear surface inside the data, the ellipsoid's 0 m far from it), or
/// nothing to compare (the fall from the data's edge to the ellipsoid).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reference {
    /// Inside the data: the source's bilinear surface, metres.
    Data(f64),
    /// Far from the data: the ellipsoid.
    Ellipsoid,
    /// Between: not compared.
    Skip,
}

impl SourceGrid<'_> {
    /// The source's bilinear surface at WGS 84 `(lon, lat)`: `None` outside
    /// its sample-centre rectangle or next to a void.
    pub fn bilinear(&self, lon: f64, lat: f64) -> Option<f64> {
        let [x, y] = self.transform.from_lonlat(lon, lat)?;
        let g = self.grid.georef();
        let (x0, y0) = g.sample_xy(0.0, 0.0);
        let (c, r) = ((x - x0) / g.pixel_x, (y - y0) / g.pixel_y);
        let (w, h) = (
            self.grid.width() as f64 - 1.0,
            self.grid.height() as f64 - 1.0,
        );
        if !(0.0..=w).contains(&c) || !(0.0..=h).contains(&r) {
            return None;
        }
        let (i, j) = (
            (c as usize).min(self.grid.width() - 2),
            (r as usize).min(self.grid.height() - 2),
        );
        let (fx, fy) = (c - i as f64, r - j as f64);
        let z = |a: usize, b: usize| f64::from(self.grid.get(a, b));
        let top = z(i, j) + (z(i + 1, j) - z(i, j)) * fx;
        let bottom = z(i, j + 1) + (z(i + 1, j + 1) - z(i, j + 1)) * fx;
        let v = top + (bottom - top) * fy;
        (!v.is_nan()).then_some(v)
    }
}

/// The reference of `sources` at WGS 84 `(lon, lat)`: the first source's
/// bilinear surface that holds the point; the ellipsoid where the point is
/// farther than `margin_deg` degrees from every rectangle of `footprints`
/// (`[west, south, east, north]`); nothing to compare in between.
pub fn reference_at(
    sources: &[SourceGrid<'_>],
    footprints: &[[f64; 4]],
    margin_deg: f64,
    lon: f64,
    lat: f64,
) -> Reference {
    reference_turns(sources, footprints, margin_deg, [lon, lat], false)
}

/// [`reference_at`], the point also looked for a turn east and west when
/// `wrap`.
fn reference_turns(
    sources: &[SourceGrid<'_>],
    footprints: &[[f64; 4]],
    margin_deg: f64,
    [lon, lat]: [f64; 2],
    wrap: bool,
) -> Reference {
    let lons = turns(wrap).iter().map(|k| lon + k);
    if let Some(z) = lons
        .clone()
        .find_map(|l| sources.iter().find_map(|s| s.bilinear(l, lat)))
    {
        return Reference::Data(z);
    }
    let near = footprints.iter().any(|f| {
        lons.clone().any(|lon| {
            lon >= f[0] - margin_deg
                && lon <= f[2] + margin_deg
                && lat >= f[1] - margin_deg
                && lat <= f[3] + margin_deg
        })
    });
    if near {
        Reference::Skip
    } else {
        Reference::Ellipsoid
    }
}

/// What tiles are checked against as drawn: the source's samples, and the
/// reference surface (the source's bilinear surface in the data, the
/// ellipsoid far from it).
pub struct Against<'a> {
    /// The source's samples.
    pub samples: SourceSamples<'a>,
    /// The reference at a longitude and latitude.
    pub reference: Box<dyn Fn(f64, f64) -> Reference + Sync + 'a>,
}

impl<'a> Against<'a> {
    /// Against `sources`, whose data lie in `footprints` (`[west, south,
    /// east, north]` degrees): the ellipsoid is checked farther than
    /// `margin_deg` from them.
    pub fn new(sources: Vec<SourceGrid<'a>>, footprints: Vec<[f64; 4]>, margin_deg: f64) -> Self {
        Against::with_wrap(sources, footprints, margin_deg, false)
    }

    /// [`Against::new`] for data across the antimeridian: samples and
    /// points are also looked for a turn east and west, so sources and
    /// `footprints` may give longitudes beyond 180° or below -180°.
    pub fn across_antimeridian(
        sources: Vec<SourceGrid<'a>>,
        footprints: Vec<[f64; 4]>,
        margin_deg: f64,
    ) -> Self {
        Against::with_wrap(sources, footprints, margin_deg, true)
    }

    fn with_wrap(
        sources: Vec<SourceGrid<'a>>,
        footprints: Vec<[f64; 4]>,
        margin_deg: f64,
        wrap: bool,
    ) -> Self {
        let samples = SourceSamples::with_wrap(&sources, wrap);
        let reference = Box::new(move |lon: f64, lat: f64| {
            reference_turns(&sources, &footprints, margin_deg, [lon, lat], wrap)
        });
        Against { samples, reference }
    }
}

impl std::fmt::Debug for Against<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Against")
            .field("samples", &self.samples)
            .finish_non_exhaustive()
    }
}

/// What [`check_random`] found.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RandomCheck {
    /// Points drawn.
    pub points: u64,
    /// Largest |drawn − bilinear source| over points inside the data
    /// (between samples: reported, not bounded), metres.
    pub data_m: f64,
    /// Largest |drawn height| over points on the ellipsoid far from the data.
    pub ellipsoid_m: f64,
}

impl RandomCheck {
    /// Both together.
    pub fn merge(self, o: RandomCheck) -> RandomCheck {
        RandomCheck {
            points: self.points + o.points,
            data_m: self.data_m.max(o.data_m),
            ellipsoid_m: self.ellipsoid_m.max(o.ellipsoid_m),
        }
    }
}

/// `per_triangle` random points of each flat ECEF triangle of `tile` (seed
/// `seed`), taken back to geodetic coordinates and compared with
/// `reference` at their footprint.
pub fn check_random(
    tile: &DrawnTile<'_>,
    per_triangle: usize,
    seed: u64,
    reference: &dyn Fn(f64, f64) -> Reference,
) -> RandomCheck {
    let mut state = seed | 1;
    let mut rnd = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut out = RandomCheck::default();
    for t in &tile.tile.triangles {
        let [a, b, c] = t.map(|i| tile.xyz[i as usize]);
        for _ in 0..per_triangle {
            let (mut u, mut v) = (rnd(), rnd());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let p = [0, 1, 2].map(|k| a[k] + u * (b[k] - a[k]) + v * (c[k] - a[k]));
            let [lon, lat, h] = geodetic(p);
            out.points += 1;
            match reference(lon, lat) {
                Reference::Data(z) => out.data_m = out.data_m.max((h - z).abs()),
                Reference::Ellipsoid => out.ellipsoid_m = out.ellipsoid_m.max(h.abs()),
                Reference::Skip => {}
            }
        }
    }
    out
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::decode::Header;
    use cota_core::{Crs, GeoRef, LonLat};

    /// A tile of two flat triangles over 1° at the equator, every vertex at
    /// 0 m: the drawn surface sags below the ellipsoid by the chord's
    /// sagitta, which the sample check measures.
    #[test]
    fn a_flat_tile_sags_by_its_chord() {
        let m = 32767;
        let tile = DecodedTile {
            header: Header {
                center: [0.0; 3],
                min_height_m: 0.0,
                max_height_m: 0.0,
                sphere_center: [0.0; 3],
                sphere_radius_m: 0.0,
                horizon_occlusion_point: [0.0; 3],
            },
            u: vec![0, m, m, 0],
            v: vec![0, 0, m, m],
            height: vec![0; 4],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            edges: Default::default(),
            wide_indices: false,
            normals: None,
            water_mask: None,
            metadata: None,
        };
        let drawn = DrawnTile::new(&tile, [10.0, 0.0, 11.0, 1.0]);
        let g = GeoRef {
            crs: Crs::WGS84,
            origin_x: 10.0,
            origin_y: 1.0,
            pixel_x: 0.1,
            pixel_y: -0.1,
            pixel_is: PixelIs::Point,
            known: true,
        };
        let grid = HeightGrid::new(11, 11, vec![0.0; 121], g).unwrap();
        let samples = SourceSamples::new(&[SourceGrid {
            grid: &grid,
            transform: &LonLat,
        }]);
        let r = check_samples(&drawn, &samples);
        assert_eq!(r.samples - r.beside, r.samples);
        assert!(r.samples >= 121, "{r:?}");
        // The diagonal is about 157 km: its sagitta is about 480 m.
        assert!(r.max_error_m > 300.0 && r.max_error_m < 700.0, "{r:?}");
        let rnd = check_random(&drawn, 20, 1, &|_, _| Reference::Ellipsoid);
        assert!(
            rnd.ellipsoid_m > 100.0 && rnd.ellipsoid_m < 700.0,
            "{rnd:?}"
        );
    }
}
