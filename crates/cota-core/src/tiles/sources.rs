//! Several DEMs, in any CRS and at any resolution, on one lattice: what
//! `cota tiles` and `cota serve` do with projected inputs (most lidar and
//! national DEMs), with inputs of different resolutions side by side
//! (paper 001's mosaic of DEMs of different sizes), and with tiles whose
//! samples do not line up (Copernicus-style 1° tiles whose width shrinks
//! with latitude, with or without a shared edge).
//!
//! Paper `001_49f2c365e8c41172.txt` joins DEMs of different sizes and
//! resolutions into one region without cracks; here every input is
//! resampled **once**, onto the tiling's geographic lattice, through its own
//! map to WGS 84 longitude/latitude ([`crate::grid::GeoTransform`]; the
//! projections themselves live in `cota-io`).
//!
//! # Heights
//! At each lattice point (a longitude and latitude), the sources in their
//! given order (finest first):
//! 1. the first whose sample-centre rectangle holds the point gives its
//!    bilinear surface there (so where sources overlap, the finest wins);
//! 2. else, where the point lies within half a pixel of one or more
//!    sources' rectangles (the gap between tiles without a shared edge, or
//!    between sources that merely abut), their surfaces clamped to their
//!    rectangles, weighted by the inverse of the distance to each: across
//!    a gap between two tiles, the linear interpolation of their edges, so
//!    no crack and no seam of NaN;
//! 3. else (beyond the data) the nearest source's edge, held for one
//!    lattice cell, falling to 0 m over [`super::lattice::ramp_cells`]
//!    cells along [`super::lattice::ramp_factor`]: the ellipsoid, as for a
//!    single source.
//!
//! # Samples
//! Every source sample counts (the fit, the errors against the source, the
//! checks) except where an earlier source (finer) covers it: there the
//! tiles follow the finer DEM, and the coarser one's samples would only
//! measure the two DEMs' disagreement.
//!
//! # Coverage
//! Each source's footprint is its sample-centre rectangle's boundary,
//! taken through its map (densified: a projected rectangle is curved on
//! the lattice); a tile is made when its square meets one with a positive
//! area ([`Coverage`]).
//!
//! # Across the antimeridian
//! Maps give longitudes in their own convention (a projected DEM over Fiji
//! comes back as 179.9° and -179.9°, a geographic grid may run from 179.5°
//! to 180.5°, two SRTM tiles E179 and W180 lie at both ends of the world).
//! The lattice counts its columns from 0° instead of 180° W
//! ([`GeographicScheme::from_greenwich`]) when the footprints, longitudes
//! taken modulo 360°, are narrower so than as given (or are only contiguous
//! so); each footprint is then placed with its longitudes modulo 360°, and
//! each source is read at the longitude nearest its own centre's (`±360°`),
//! so a source at -179.9° answers a lattice point at 180.1°. Data across
//! both the antimeridian and the prime meridian are refused
//! ([`TilesError::AcrossAntimeridian`]), as is a footprint around a pole
//! ([`TilesError::AroundPole`]).

use rayon::prelude::*;

use super::coverage::Coverage;
use super::error::TilesError;
use super::fit::fit;
use super::lattice::{
    choose_window, fit_tolerance_m, ramp_cells, ramp_factor, scheme_for_pixel, Lattice,
    LatticeFrame, LatticeOptions,
};
use super::samples::{Listed, SampleSet};
use super::scheme::GeographicScheme;
use crate::grid::{GeoRef, GeoTransform, HeightGrid, MAX_SAMPLES};
use crate::progress::{Counter, Progress, Stages};

/// One input DEM placed on the Earth.
#[derive(Debug, Clone, Copy)]
pub struct Source<'a> {
    /// Its samples (no voids: fill them first).
    pub grid: &'a HeightGrid,
    /// Its CRS's map to WGS 84 longitude/latitude.
    pub transform: &'a dyn GeoTransform,
}

/// Points along a side of a footprint's boundary.
const SIDE_POINTS: usize = 64;

/// A source with what the resampling needs of it.
struct Placed<'a> {
    src: Source<'a>,
    /// Its footprint on the lattice (global lattice coordinates), closed.
    polygon: Vec<[f64; 2]>,
    /// Its footprint's bounding box grown by the ramp, `[x0, y0, x1, y1]`.
    reach: [f64; 4],
    /// A pixel's ground size in lattice cells (the smaller side).
    pixel_cells: f64,
    /// The longitude its map gives at its centre, when the lattice counts
    /// from 0° (its queries are brought within 180° of it); else `None`.
    own_lon: Option<f64>,
}

impl Placed<'_> {
    /// Longitude `lon` in the source's own convention (see the module docs).
    fn own(&self, lon: f64) -> f64 {
        match self.own_lon {
            Some(c) => lon - 360.0 * ((lon - c) / 360.0).round(),
            None => lon,
        }
    }
}

/// The lattice of several sources (its frame's source fields describe the
/// first source; its coverage, their footprints) and their samples.
#[derive(Debug)]
pub struct Resampled {
    /// The lattice.
    pub lattice: Lattice,
    /// The sources' samples that count (see the module docs).
    pub samples: Listed,
}

impl Lattice {
    /// Resamples `sources` (finest first, no voids) onto the tiling's
    /// lattice (see the module docs), fitted to their samples
    /// ([`super::fit`]).
    ///
    /// # Errors
    /// [`TilesError::BadOptions`] for no source or a source the map cannot
    /// place, [`TilesError::OutsideWorld`], [`TilesError::TooLarge`],
    /// [`TilesError::Voids`].
    pub fn resample_sources(
        sources: &[Source<'_>],
        opts: &LatticeOptions,
    ) -> Result<Resampled, TilesError> {
        Lattice::resample_sources_with_progress(sources, opts, crate::progress::NONE)
    }

    /// [`Lattice::resample_sources`], telling `progress(done, total)` as it
    /// goes: the lattice's rows interpolated, the samples listed, the fit's
    /// rounds, weighted by their share of the time (in thousandths,
    /// [`crate::progress`]).
    ///
    /// # Errors
    /// As [`Lattice::resample_sources`].
    pub fn resample_sources_with_progress(
        sources: &[Source<'_>],
        opts: &LatticeOptions,
        progress: Progress<'_>,
    ) -> Result<Resampled, TilesError> {
        for s in sources {
            if let Some((col, row)) = s.grid.first_void() {
                return Err(TilesError::Voids { col, row });
            }
        }
        let (frame, placed) = frame_of(sources, opts)?;
        let window = frame.window;
        let (w, h) = (window[2] - window[0] + 1, window[3] - window[1] + 1);
        if w.checked_mul(h).is_none_or(|n| n > MAX_SAMPLES) {
            return Err(TilesError::TooLarge {
                width: w,
                height: h,
            });
        }
        let stages = Stages::new(progress, &SOURCES_WEIGHTS);
        let mut heights = fill(&placed, &frame, &stages.stage(0));
        stages.finish(0);
        let samples = Listed::new(sample_positions(&placed, &frame.scheme));
        stages.finish(1);
        let fitted = fit(
            &mut heights,
            [w as usize, h as usize],
            [window[0], window[1]],
            &samples,
            frame.fit_m,
            window,
            &stages.stage(2),
        );
        stages.finish(2);
        let coverage = Coverage {
            polygons: placed.into_iter().map(|p| p.polygon).collect(),
        };
        let lattice = Lattice::from_heights(frame, heights, fitted.residual_m, coverage)?;
        Ok(Resampled { lattice, samples })
    }
}

impl LatticeFrame {
    /// The frame [`Lattice::resample_sources`] resamples `sources` (finest
    /// first) in, without resampling: what the lattice's size depends on
    /// ([`mod@super::estimate`]).
    ///
    /// # Errors
    /// As [`Lattice::resample_sources`], but for voids.
    pub fn for_sources(
        sources: &[Source<'_>],
        opts: &LatticeOptions,
    ) -> Result<LatticeFrame, TilesError> {
        frame_of(sources, opts).map(|(frame, _)| frame)
    }
}

/// The frame of `sources` and each placed on the scheme.
fn frame_of<'a>(
    sources: &[Source<'a>],
    opts: &LatticeOptions,
) -> Result<(LatticeFrame, Vec<Placed<'a>>), TilesError> {
    let Some(first) = sources.first() else {
        return Err(TilesError::BadOptions(
            "expected at least one source, found none".into(),
        ));
    };
    let pixel_deg = sources
        .iter()
        .map(pixel_deg)
        .collect::<Result<Vec<f64>, TilesError>>()?;
    let finest = pixel_deg.iter().copied().fold(f64::INFINITY, f64::min);
    let mut scheme = scheme_for_pixel(finest, opts)?;
    let rings = sources
        .iter()
        .map(ring_of)
        .collect::<Result<Vec<_>, TilesError>>()?;
    scheme.from_greenwich = from_greenwich(&rings)?;
    let placed = sources
        .iter()
        .zip(rings)
        .zip(&pixel_deg)
        .map(|((s, ring), &p)| place(*s, ring, p, &scheme))
        .collect::<Result<Vec<Placed<'_>>, TilesError>>()?;
    let fp = bounds(&placed, &scheme)?;
    let (align_zoom, window) = choose_window(&scheme, fp);
    let frame = LatticeFrame {
        scheme,
        footprint: fp,
        window,
        align_zoom,
        source_georef: first.grid.georef().clone(),
        source_size: [first.grid.width(), first.grid.height()],
        fit_m: fit_tolerance_m(&scheme, finest, opts),
    };
    Ok((frame, placed))
}

/// A pixel's ground size, in degrees of latitude (the smaller of its two
/// sides, at the grid's centre).
fn pixel_deg(s: &Source<'_>) -> Result<f64, TilesError> {
    let g = s.grid.georef();
    let (c, r) = (s.grid.width() as f64 / 2.0, s.grid.height() as f64 / 2.0);
    let at = |dc: f64, dr: f64| {
        let (x, y) = g.sample_xy(c + dc, r + dr);
        s.transform.to_lonlat(x, y)
    };
    let (Some(o), Some(e), Some(n)) = (at(0.0, 0.0), at(1.0, 0.0), at(0.0, 1.0)) else {
        return Err(unplaced(g));
    };
    let [mx, my] = crate::grid::metres_per_degree(o[1]);
    let side = |p: [f64; 2]| ((p[0] - o[0]) * mx).hypot((p[1] - o[1]) * my) / my;
    let d = side(e).min(side(n));
    if d.is_finite() && d > 0.0 {
        Ok(d)
    } else {
        Err(unplaced(g))
    }
}

fn unplaced(g: &GeoRef) -> TilesError {
    TilesError::BadOptions(format!(
        "expected a source its CRS ({}) can place on the Earth, found positions it cannot take to longitude/latitude",
        g.crs
    ))
}

/// The source's footprint: its sample-centre rectangle's boundary,
/// densified, as its map gives it in longitude and latitude.
fn ring_of(s: &Source<'_>) -> Result<Vec<[f64; 2]>, TilesError> {
    let g = s.grid.georef();
    let (w, h) = (s.grid.width() as f64 - 1.0, s.grid.height() as f64 - 1.0);
    let n = SIDE_POINTS as f64;
    (0..SIDE_POINTS)
        .map(|k| (k as f64 / n * w, 0.0))
        .chain((0..SIDE_POINTS).map(|k| (w, k as f64 / n * h)))
        .chain((0..SIDE_POINTS).map(|k| (w - k as f64 / n * w, h)))
        .chain((0..SIDE_POINTS).map(|k| (0.0, h - k as f64 / n * h)))
        .map(|(c, r)| {
            let (x, y) = g.sample_xy(c, r);
            s.transform.to_lonlat(x, y).ok_or_else(|| unplaced(g))
        })
        .collect()
}

/// The source's footprint on the lattice and its reach.
fn place<'a>(
    s: Source<'a>,
    ring: Vec<[f64; 2]>,
    pixel_deg: f64,
    scheme: &GeographicScheme,
) -> Result<Placed<'a>, TilesError> {
    let g = s.grid.georef();
    let d = scheme.cell_deg();
    let polygon: Vec<[f64; 2]> = ring
        .iter()
        .map(|&[lon, lat]| [scheme.col_of(scheme.lattice_lon(lon)), (90.0 - lat) / d])
        .collect();
    let own_lon = if scheme.from_greenwich {
        let (w, h) = (s.grid.width() as f64 - 1.0, s.grid.height() as f64 - 1.0);
        let (x, y) = g.sample_xy(w / 2.0, h / 2.0);
        Some(s.transform.to_lonlat(x, y).ok_or_else(|| unplaced(g))?[0])
    } else {
        None
    };
    let pixel_cells = pixel_deg / d;
    let grow = 2.0 + ramp_cells(scheme) + pixel_cells;
    let mut reach = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in &polygon {
        reach = [
            reach[0].min(p[0]),
            reach[1].min(p[1]),
            reach[2].max(p[0]),
            reach[3].max(p[1]),
        ];
    }
    reach = [
        reach[0] - grow,
        reach[1] - grow,
        reach[2] + grow,
        reach[3] + grow,
    ];
    Ok(Placed {
        src: s,
        polygon,
        reach,
        pixel_cells,
        own_lon,
    })
}

/// Whether the lattice counts its columns from 0° (see the module docs):
/// when the footprints, longitudes modulo 360°, are narrower than as given,
/// or contiguous only so.
///
/// # Errors
/// [`TilesError::AroundPole`], [`TilesError::AcrossAntimeridian`] (data
/// across both the antimeridian and the prime meridian).
fn from_greenwich(rings: &[Vec<[f64; 2]>]) -> Result<bool, TilesError> {
    for r in rings {
        around_pole(r)?;
    }
    let plain = lon_extent(rings, |l| l).filter(|e| e[0] >= -180.0 - 1e-9 && e[1] <= 180.0 + 1e-9);
    let wrapped = lon_extent(rings, |l| l.rem_euclid(360.0));
    let width = |e: [f64; 2]| e[1] - e[0];
    match (plain, wrapped) {
        (Some(p), Some(w)) => Ok(width(w) < width(p) - 1e-9),
        (Some(_), None) => Ok(false),
        (None, Some(_)) => Ok(true),
        (None, None) => {
            let lons = rings.iter().flatten().map(|p| p[0]);
            Err(TilesError::AcrossAntimeridian {
                west: lons.clone().fold(f64::INFINITY, f64::min),
                east: lons.fold(f64::NEG_INFINITY, f64::max),
            })
        }
    }
}

/// The longitudes `[min, max]` of every ring's points mapped by `f`;
/// `None` when a ring jumps by more than half the world between two
/// consecutive points (it crosses the edge of `f`'s range).
fn lon_extent(rings: &[Vec<[f64; 2]>], f: impl Fn(f64) -> f64) -> Option<[f64; 2]> {
    let mut e = [f64::INFINITY, f64::NEG_INFINITY];
    for r in rings {
        for k in 0..r.len() {
            let (a, b) = (f(r[k][0]), f(r[(k + 1) % r.len()][0]));
            if (a - b).abs() > 180.0 {
                return None;
            }
            e = [e[0].min(a), e[1].max(a)];
        }
    }
    Some(e)
}

/// Refuses a footprint that goes round a pole: its boundary's winding in
/// longitude (each step taken the short way round) is a whole turn.
fn around_pole(ring: &[[f64; 2]]) -> Result<(), TilesError> {
    let n = ring.len();
    let winding: f64 = (0..n)
        .map(|k| {
            let dx = ring[(k + 1) % n][0] - ring[k][0];
            dx - 360.0 * (dx / 360.0).round()
        })
        .sum();
    if winding.abs() <= 180.0 {
        return Ok(());
    }
    let north = ring.iter().map(|p| p[1]).sum::<f64>() > 0.0;
    Err(TilesError::AroundPole {
        pole: if north { "north" } else { "south" },
    })
}

/// The data's bounding box on the lattice, `[west col, north row, east col,
/// south row]`, inside the world.
fn bounds(placed: &[Placed<'_>], scheme: &GeographicScheme) -> Result<[f64; 4], TilesError> {
    let mut fp = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in placed.iter().flat_map(|p| &p.polygon) {
        fp = [
            fp[0].min(p[0]),
            fp[1].min(p[1]),
            fp[2].max(p[0]),
            fp[3].max(p[1]),
        ];
    }
    let (wmax, hmax) = (2.0 * scheme.root_cells() as f64, scheme.root_cells() as f64);
    let eps = 1e-9 * wmax;
    if fp[0] < -eps || fp[1] < -eps || fp[2] > wmax + eps || fp[3] > hmax + eps {
        let d = scheme.cell_deg();
        return Err(TilesError::OutsideWorld {
            west: scheme.lon_of(fp[0]),
            south: 90.0 - fp[3] * d,
            east: scheme.lon_of(fp[2]),
            north: 90.0 - fp[1] * d,
        });
    }
    Ok([
        fp[0].max(0.0),
        fp[1].max(0.0),
        fp[2].min(wmax),
        fp[3].min(hmax),
    ])
}

/// The relative times of [`Lattice::resample_sources_with_progress`]'s
/// stages: the interpolation, the samples' list, the fit (estimated).
const SOURCES_WEIGHTS: [usize; 3] = [50, 20, 30];

/// The heights of the window (see the module docs), in parallel over rows,
/// telling `progress(rows_done, rows)`.
fn fill(placed: &[Placed<'_>], frame: &LatticeFrame, progress: Progress<'_>) -> Vec<f32> {
    let win = frame.window;
    let s = &frame.scheme;
    let w = (win[2] - win[0] + 1) as usize;
    let h = (win[3] - win[1] + 1) as usize;
    let ramp = ramp_cells(s);
    let mut out = vec![0f32; w * h];
    let rows = Counter::new(progress, h);
    out.par_chunks_mut(w).enumerate().for_each(|(j, line)| {
        rows.add(1);
        let y = (win[1] + j as u64) as f64;
        for (i, o) in line.iter_mut().enumerate() {
            let x = (win[0] + i as u64) as f64;
            *o = height_at(placed, s, x, y, ramp) as f32;
        }
    });
    out
}

/// The height at global lattice `(x, y)`.
fn height_at(placed: &[Placed<'_>], s: &GeographicScheme, x: f64, y: f64, ramp: f64) -> f64 {
    let (lon, lat) = (s.lon_of(x), s.lat_of(y));
    let (mut sum, mut weight) = (0.0, 0.0);
    let mut nearest = (f64::INFINITY, 0.0);
    for p in placed {
        let r = p.reach;
        if x < r[0] || x > r[2] || y < r[1] || y > r[3] {
            continue;
        }
        let Some((d, v)) = clamped(p.src, p.own(lon), lat) else {
            continue;
        };
        if d <= 0.0 {
            return v;
        }
        if d <= 0.5 {
            sum += v / d;
            weight += 1.0 / d;
        }
        let cells = d * p.pixel_cells;
        if cells < nearest.0 {
            nearest = (cells, v);
        }
    }
    if weight > 0.0 {
        return sum / weight;
    }
    let (cells, v) = nearest;
    // The edge held one cell beyond the data, then down to 0 m.
    v * ramp_factor(cells, ramp)
}

/// How far (in the source's pixels) WGS 84 `(lon, lat)` lies beyond the
/// source's sample-centre rectangle, and its bilinear surface at the
/// nearest point of the rectangle; `None` where its map cannot take the
/// point.
fn clamped(s: Source<'_>, lon: f64, lat: f64) -> Option<(f64, f64)> {
    let [x, y] = s.transform.from_lonlat(lon, lat)?;
    let g = s.grid.georef();
    let (x0, y0) = g.sample_xy(0.0, 0.0);
    let (c, r) = ((x - x0) / g.pixel_x, (y - y0) / g.pixel_y);
    let (w, h) = (s.grid.width() as f64 - 1.0, s.grid.height() as f64 - 1.0);
    if !(c.is_finite() && r.is_finite()) {
        return None;
    }
    let beyond = |v: f64, n: f64| (-v).max(v - n).max(0.0);
    let d = beyond(c, w).max(beyond(r, h));
    Some((d, bilinear(s.grid, c.clamp(0.0, w), r.clamp(0.0, h))))
}

/// The bilinear surface of `g` at fractional column `c`, row `r` (inside).
fn bilinear(g: &HeightGrid, c: f64, r: f64) -> f64 {
    let (i, j) = (
        (c as usize).min(g.width() - 2),
        (r as usize).min(g.height() - 2),
    );
    let (fx, fy) = (c - i as f64, r - j as f64);
    let z = |a: usize, b: usize| f64::from(g.get(a, b));
    let top = z(i, j) + (z(i + 1, j) - z(i, j)) * fx;
    let bottom = z(i, j + 1) + (z(i + 1, j + 1) - z(i, j + 1)) * fx;
    top + (bottom - top) * fy
}

/// Every sample that counts (see the module docs) as `[x, y, height_m]` on
/// the lattice, the sources in order, each row-major.
fn sample_positions(placed: &[Placed<'_>], scheme: &GeographicScheme) -> Vec<[f64; 3]> {
    let d = scheme.cell_deg();
    let per_source: Vec<Vec<[f64; 3]>> = placed
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let g = p.src.grid;
            let geo = g.georef();
            (0..g.height())
                .into_par_iter()
                .flat_map_iter(|r| {
                    (0..g.width()).filter_map(move |c| {
                        let (x, y) = geo.sample_xy(c as f64, r as f64);
                        let [lon, lat] = p.src.transform.to_lonlat(x, y)?;
                        let covered = placed[..k].iter().any(|q| {
                            clamped(q.src, q.own(lon), lat).is_some_and(|(d, _)| d <= 0.0)
                        });
                        let x = scheme.col_of(scheme.lattice_lon(lon));
                        (!covered).then(|| [x, (90.0 - lat) / d, f64::from(g.get(c, r))])
                    })
                })
                .collect()
        })
        .collect();
    per_source.into_iter().flatten().collect()
}

/// The largest and the root mean square |lattice − sample| over `samples`
/// (the lattice's unit-triangle surface at each sample).
pub fn deviation_of(lattice: &Lattice, samples: &impl SampleSet) -> super::lattice::Deviation {
    deviation_of_with_progress(lattice, samples, crate::progress::NONE)
}

/// Samples [`deviation_of_with_progress`] counts at a time.
const DEVIATION_CHUNK: usize = 4096;

/// [`deviation_of`], telling `progress(chunks_done, chunks)` as it goes
/// (chunks of a few thousand samples).
pub fn deviation_of_with_progress(
    lattice: &Lattice,
    samples: &impl SampleSet,
    progress: Progress<'_>,
) -> super::lattice::Deviation {
    let n = samples.len();
    let chunks = Counter::new(progress, n.div_ceil(DEVIATION_CHUNK));
    let (max, sum, n) = (0..n.div_ceil(DEVIATION_CHUNK))
        .into_par_iter()
        .map(|c| {
            chunks.add(1);
            (c * DEVIATION_CHUNK..((c + 1) * DEVIATION_CHUNK).min(n))
                .map(|k| {
                    let [x, y, h] = samples.sample(k);
                    let d = lattice.unit_surface_at(x, y) - h;
                    (d.abs(), d * d, 1usize)
                })
                .fold((0.0, 0.0, 0), |a: (f64, f64, usize), b| {
                    (a.0.max(b.0), a.1 + b.1, a.2 + b.2)
                })
        })
        .reduce(
            || (0.0, 0.0, 0),
            |a, b| (a.0.max(b.0), a.1 + b.1, a.2 + b.2),
        );
    super::lattice::Deviation {
        max_m: max,
        rms_m: if n > 0 { (sum / n as f64).sqrt() } else { 0.0 },
        samples: n,
    }
}

#[cfg(test)]
mod test {
    use super::*;

    fn rect(w: f64, s: f64, e: f64, n: f64) -> Vec<[f64; 2]> {
        vec![[w, s], [e, s], [e, n], [w, n]]
    }

    #[test]
    fn the_lattice_counts_from_greenwich_only_across_the_antimeridian() {
        let (e179, w180) = (rect(179.0, 0.0, 180.0, 1.0), rect(-180.0, 0.0, -179.0, 1.0));
        assert_eq!(from_greenwich(&[e179.clone(), w180.clone()]), Ok(true));
        // Touching 180° from one side: as before.
        assert_eq!(from_greenwich(&[e179]), Ok(false));
        assert_eq!(from_greenwich(&[w180]), Ok(false));
        assert_eq!(from_greenwich(&[rect(-1.0, 0.0, 1.0, 1.0)]), Ok(false));
        assert_eq!(from_greenwich(&[rect(179.5, 0.0, 180.5, 1.0)]), Ok(true));
        // Fiji as a projection's inverse gives it.
        let fiji = vec![
            [179.9, -17.0],
            [-179.9, -17.0],
            [-179.9, -16.0],
            [179.9, -16.0],
        ];
        assert_eq!(from_greenwich(&[fiji]), Ok(true));
        let both = vec![
            [-10.0, 0.0],
            [90.0, 0.0],
            [179.0, 0.0],
            [-170.0, 0.0],
            [-170.0, 1.0],
            [179.0, 1.0],
            [90.0, 1.0],
            [-10.0, 1.0],
        ];
        assert!(matches!(
            from_greenwich(&[both]),
            Err(TilesError::AcrossAntimeridian { .. })
        ));
        let pole = vec![[0.0, 80.0], [90.0, 80.0], [180.0, 80.0], [-90.0, 80.0]];
        assert!(matches!(
            from_greenwich(&[pole]),
            Err(TilesError::AroundPole { pole: "north" })
        ));
    }
}
