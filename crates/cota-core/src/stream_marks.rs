//! Streaming a criterion-driven refinement with fictitious points: only the
//! selected points' heights travel; fictitious points cost one flag.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2.2 (fictitious points: needed only to
//! complete the hierarchy, height interpolated on their diagonal) and §3
//! ("Transmisión progresiva": fictitious points are never sent, the receiver
//! adds them itself). The input is the closed [`Marks`] of
//! [`crate::refine::refine_marks`] in any [`Mode`].
//!
//! 1. **Walk** the tree from the roots as `refine::triangulate` does: straddling
//!    triangles split without a bit; every inside non-unit triangle codes one
//!    bit, "this side of my split point splits" (adaptive, per level and per
//!    whether the point is already present, so the second side of a watertight
//!    or selected point costs almost nothing).
//! 2. **New points.** The first time a point becomes present, one bit (per
//!    level) says whether it is *selected* (real height) or *fictitious*. A
//!    selected point sends its quantised height as a residual against
//!    `round(((z_a + z_b) / 2) / quantum)` (the diagonal's midpoint, with
//!    fictitious ends at their interpolated height); a fictitious point sends
//!    nothing. Split points of straddling triangles inside the grid are the
//!    border's selected points: height, no flag.
//! 3. **Receiver.** It collects the selected points, rebuilds the closed marks
//!    (`Marks::seed_border`, `select`, `close`: the closure of a selection is
//!    unique, so it equals the sender's), and triangulates with the decoded
//!    heights: the mesh equals the sender's `refine` mesh vertex for vertex
//!    when the heights are on the quantum lattice.
//!
//! # Bit layout
//! Header kind 1 (conforming), 2 (fictitious, watertight) or 3 (fictitious,
//! faithful) of [`crate::stream`]; exactly one step: `max_error_m: f32` (the
//! bound the sender states, e.g. the criterion's `E`), then one range-coded
//! block: in walk order, `split: bit` per inside candidate triangle, then for
//! a newly present point `selected: bit` and, when selected (or on the border),
//! its residual ([`crate::stream_coder::ResidualModel`], one model per level).

use crate::fictitious::Marks;
use crate::grid::{GeoRef, HeightGrid};
use crate::hierarchy::{Placement, Pt, Tri};
use crate::mesh::Mesh;
use crate::refine::{triangulate, Mode};
use crate::stream::{
    corner_points, level, quantize, residual_ctx, EncodedStep, EncodedStream, Models, State,
    StreamError, StreamHeader, StreamKind, StreamOptions, MAX_Q, UNKNOWN,
};
use crate::stream_coder::{RangeDecoder, RangeEncoder};

/// Per-sample flags of the walk.
const SEL: u8 = 1;
/// Split bits of the two sides of a diamond.
const SIDES: [u8; 2] = [2, 4];

/// Which side of `m`'s diamond the triangle with apex `c` lies on.
#[inline]
fn side(c: Pt, m: Pt) -> usize {
    usize::from((c[1], c[0]) >= (m[1], m[0]))
}

/// The two directions of the walk.
trait MarksCoder {
    fn split(&mut self, ctx: usize, t: &Tri) -> Result<bool, String>;
    fn selected(&mut self, ctx: usize, m: Pt) -> Result<bool, String>;
    fn height(&mut self, ctx: usize, i: usize, pred: i64) -> Result<i64, String>;
}

struct Enc<'a> {
    enc: RangeEncoder,
    models: &'a mut Models,
    marks: &'a Marks,
    q: &'a [i64],
    new_points: usize,
}

impl MarksCoder for Enc<'_> {
    fn split(&mut self, ctx: usize, t: &Tri) -> Result<bool, String> {
        let yes = self.marks.splits(t);
        self.enc.bit(&mut self.models.side[ctx], yes);
        Ok(yes)
    }

    fn selected(&mut self, ctx: usize, m: Pt) -> Result<bool, String> {
        let yes = self.marks.is_selected(m);
        self.enc.bit(&mut self.models.select[ctx], yes);
        Ok(yes)
    }

    fn height(&mut self, ctx: usize, i: usize, pred: i64) -> Result<i64, String> {
        let q = self.q[i];
        self.models.residual[ctx].encode(&mut self.enc, q - pred);
        self.new_points += 1;
        Ok(q)
    }
}

struct Dec<'a, 'b> {
    dec: RangeDecoder<'b>,
    models: &'a mut Models,
    new_points: usize,
}

impl MarksCoder for Dec<'_, '_> {
    fn split(&mut self, ctx: usize, _t: &Tri) -> Result<bool, String> {
        Ok(self.dec.bit(&mut self.models.side[ctx]))
    }

    fn selected(&mut self, ctx: usize, _m: Pt) -> Result<bool, String> {
        Ok(self.dec.bit(&mut self.models.select[ctx]))
    }

    fn height(&mut self, ctx: usize, _i: usize, pred: i64) -> Result<i64, String> {
        let r = self.models.residual[ctx].decode(&mut self.dec);
        self.new_points += 1;
        match pred.checked_add(r) {
            Some(q) if q.abs() < MAX_Q => Ok(q),
            _ => Err(format!(
                "a height below 2^40 quanta, found a residual of {r} on a prediction of {pred}"
            )),
        }
    }
}

/// The walk's own state: flags and prediction heights.
struct Walk<'s> {
    st: &'s mut State,
    flags: Vec<u8>,
    z: Vec<f64>,
    quantum_m: f64,
}

impl Walk<'_> {
    fn new(st: &mut State, quantum_m: f64) -> Walk<'_> {
        let z =
            st.q.iter()
                .map(|&q| {
                    if q == UNKNOWN {
                        f64::NAN
                    } else {
                        q as f64 * quantum_m
                    }
                })
                .collect();
        let n = st.q.len();
        Walk {
            st,
            flags: vec![0; n],
            z,
            quantum_m,
        }
    }

    fn z_at(&self, p: Pt) -> Option<f64> {
        let h = &self.st.hier;
        if !h.contains(p) {
            return None;
        }
        let v = self.z[h.index(p)];
        (!v.is_nan()).then_some(v)
    }

    fn learn<C: MarksCoder>(&mut self, c: &mut C, t: &Tri, i: usize) -> Result<(), String> {
        let pred_m = match (self.z_at(t.a), self.z_at(t.b)) {
            (Some(a), Some(b)) => (a + b) / 2.0,
            _ => {
                let v: Vec<f64> = [t.a, t.b, t.c]
                    .into_iter()
                    .filter_map(|p| self.z_at(p))
                    .collect();
                if v.is_empty() {
                    0.0
                } else {
                    v.iter().sum::<f64>() / v.len() as f64
                }
            }
        };
        let pred = (pred_m / self.quantum_m).round();
        let pred = if pred.abs() < MAX_Q as f64 {
            pred as i64
        } else {
            0
        };
        let q = c.height(residual_ctx(level(t), 0), i, pred)?;
        self.st.q[i] = q;
        self.z[i] = q as f64 * self.quantum_m;
        Ok(())
    }

    fn walk<C: MarksCoder>(&mut self, c: &mut C, t: Tri, inside: bool) -> Result<(), String> {
        let hier = self.st.hier;
        let inside = inside
            || match hier.place(&t) {
                Placement::Outside => return Ok(()),
                Placement::Straddling => false,
                Placement::Inside => true,
            };
        if t.is_unit() {
            return Ok(());
        }
        let m = t.mid();
        if !inside {
            if hier.contains(m) {
                let i = hier.index(m);
                if self.flags[i] & SEL == 0 {
                    self.flags[i] |= SEL;
                    if self.st.q[i] == UNKNOWN {
                        self.learn(c, &t, i)?;
                    }
                }
            }
        } else {
            let i = hier.index(m);
            let present = self.flags[i] != 0;
            let lvl = level(&t);
            if !c.split(lvl * 2 + usize::from(present), &t)? {
                return Ok(());
            }
            self.flags[i] |= SIDES[side(t.c, m)];
            if !present {
                if c.selected(lvl, m)? {
                    self.flags[i] |= SEL;
                    self.learn(c, &t, i)?;
                } else {
                    match (self.z_at(t.a), self.z_at(t.b)) {
                        (Some(a), Some(b)) => self.z[i] = 0.5 * (a + b),
                        _ => return Err("a fictitious point with both diagonal ends known".into()),
                    }
                }
            }
        }
        let (c0, c1) = t.children();
        self.walk(c, c0, inside)?;
        self.walk(c, c1, inside)
    }

    fn run<C: MarksCoder>(&mut self, c: &mut C) -> Result<(), String> {
        for r in self.st.hier.roots() {
            self.walk(c, r, false)?;
        }
        Ok(())
    }
}

/// Encodes the closed `marks` of a refinement of `grid` in `mode` as a
/// one-step stream stating `max_error_m` (the bound the refinement
/// guarantees, e.g. its `MaxVerticalError`). Heights are quantised with
/// `opts.quantum_m` (`opts.max_error_m` and thresholds are ignored).
///
/// # Errors
/// [`StreamError::BadQuantum`], [`StreamError::HeightOutOfRange`],
/// [`StreamError::BadMaxError`], or [`StreamError::BadHeader`] when `marks`
/// was made for another grid size.
pub fn encode_marks(
    grid: &HeightGrid,
    marks: &Marks,
    mode: Mode,
    max_error_m: f64,
    opts: &StreamOptions,
) -> Result<EncodedStream, StreamError> {
    if max_error_m.is_nan() || max_error_m < 0.0 {
        return Err(StreamError::BadMaxError(max_error_m));
    }
    let hier = *marks.hierarchy();
    if (hier.width() as usize, hier.height() as usize) != (grid.width(), grid.height()) {
        return Err(StreamError::BadHeader {
            expected: format!("marks for the {}x{} grid", grid.width(), grid.height()),
            found: format!("marks for {}x{}", hier.width(), hier.height()),
        });
    }
    let (qgrid, lattice_exact) = quantize(grid, opts.quantum_m)?;
    let q: Vec<i64> = qgrid
        .heights()
        .iter()
        .map(|&h| (h as f64 / opts.quantum_m).round() as i64)
        .collect();
    let header = StreamHeader {
        width: hier.width(),
        height: hier.height(),
        quantum_m: opts.quantum_m,
        corners_q: corner_points(&hier).map(|c| c.map(|p| q[hier.index(p)]).unwrap_or(0)),
        kind: StreamKind::Marks(mode),
    };
    let mut state = State::new(&header);
    let mut models = Models::new();
    let mut c = Enc {
        enc: RangeEncoder::new(),
        models: &mut models,
        marks,
        q: &q,
        new_points: 0,
    };
    Walk::new(&mut state, opts.quantum_m)
        .run(&mut c)
        .map_err(|found| StreamError::BadStep {
            step: 0,
            expected: "marks the encoder can walk".into(),
            found,
        })?;
    let new_points = c.new_points;
    let stated = max_error_m as f32;
    let stated = if (stated as f64) < max_error_m {
        stated.next_up()
    } else {
        stated
    };
    let mut payload = stated.to_le_bytes().to_vec();
    payload.extend_from_slice(&c.enc.finish());
    let mesh = triangulate(&qgrid, marks, mode).mesh;
    Ok(EncodedStream {
        header,
        steps: vec![EncodedStep {
            threshold_m: max_error_m,
            max_error_m: stated as f64,
            payload,
            triangles: mesh.triangle_count(),
            vertices: mesh.vertex_count(),
            new_points,
        }],
        lattice_exact,
    })
}

/// Decodes the one step of a marks stream into `st`; returns the mesh and the
/// number of heights read.
pub(crate) fn decode(
    st: &mut State,
    models: &mut Models,
    header: &StreamHeader,
    mode: Mode,
    block: &[u8],
) -> Result<(Mesh, usize), String> {
    let mut c = Dec {
        dec: RangeDecoder::new(block),
        models,
        new_points: 0,
    };
    let mut w = Walk::new(st, header.quantum_m);
    w.run(&mut c)?;
    if c.dec.overrun() > 0 {
        return Err(format!(
            "{} bytes of coded data, found {} (truncated or corrupted)",
            block.len() + c.dec.overrun(),
            block.len()
        ));
    }
    let flags = std::mem::take(&mut w.flags);
    let hier = st.hier;
    let mut marks = Marks::new(hier, mode.closure());
    marks.seed_border();
    let wd = hier.width();
    for (i, &f) in flags.iter().enumerate() {
        if f & SEL != 0 {
            marks.select([i as u32 % wd, i as u32 / wd]);
        }
    }
    marks.close();
    let heights: Vec<f32> =
        st.q.iter()
            .map(|&q| {
                if q == UNKNOWN {
                    0.0
                } else {
                    (q as f64 * header.quantum_m) as f32
                }
            })
            .collect();
    let grid = HeightGrid::new(
        hier.width() as usize,
        hier.height() as usize,
        heights,
        GeoRef::unreferenced(1.0),
    )
    .map_err(|e| e.to_string())?;
    let mesh = triangulate(&grid, &marks, mode).mesh;
    st.marks = Some(marks);
    Ok((mesh, c.new_points))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, reason = "tests")]
mod test {
    use super::*;
    use crate::refine::{refine_marks, RefineOptions};
    use crate::stream::StreamDecoder;
    use crate::{check_mesh, CheckOptions, MaxVerticalError};

    fn grid(w: usize, h: usize) -> HeightGrid {
        let v = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                (300.0 + 50.0 * (x * 0.23).sin() * (y * 0.19).cos()).round()
                    + ((i * 7919) % 3) as f32
            })
            .collect();
        HeightGrid::new(w, h, v, GeoRef::unreferenced(30.0)).unwrap()
    }

    #[test]
    fn marks_streams_rebuild_the_refined_mesh() {
        let modes = [
            Mode::Conforming,
            Mode::Fictitious { watertight: true },
            Mode::Fictitious { watertight: false },
        ];
        for (w, h) in [(33, 33), (45, 29)] {
            let g = grid(w, h);
            for mode in modes {
                for e in [0.0, 2.0, 10.0] {
                    let crit = MaxVerticalError { max_error_m: e };
                    let opts = RefineOptions::DEFAULT.with_mode(mode);
                    let (r, marks) = refine_marks(&g, &crit, &opts).unwrap();
                    let s = encode_marks(&g, &marks, mode, e, &StreamOptions::default()).unwrap();
                    assert_eq!(s.steps.len(), 1);
                    let hb = StreamHeader::from_bytes(&s.header.to_bytes()).unwrap();
                    let mut d = StreamDecoder::new(hb);
                    d.apply_step(&s.steps[0].payload).unwrap();
                    let mesh = d.mesh();
                    assert_eq!(mesh, r.mesh, "{w}x{h} {mode:?} {e}");
                    assert!(s.steps[0].new_points <= r.transmitted_points);
                    let check = CheckOptions::conforming(e)
                        .with_conforming(mode.is_conforming())
                        .with_allow_fictitious(true);
                    check_mesh(&g, &mesh, &check).unwrap();
                    assert!(d.heights_m().unwrap().iter().all(|z| z.is_finite()));
                    // A second step is refused and changes nothing.
                    assert!(d.apply_step(&s.steps[0].payload).is_err());
                    assert_eq!(d.mesh(), r.mesh);
                }
            }
        }
    }

    #[test]
    fn corrupted_marks_payloads_never_panic() {
        let g = grid(21, 17);
        let mode = Mode::Fictitious { watertight: false };
        let crit = MaxVerticalError { max_error_m: 3.0 };
        let opts = RefineOptions::DEFAULT.with_mode(mode);
        let (_, marks) = refine_marks(&g, &crit, &opts).unwrap();
        let s = encode_marks(&g, &marks, mode, 3.0, &StreamOptions::default()).unwrap();
        let p = &s.steps[0].payload;
        for i in 4..p.len() {
            for x in [1u8, 0x80] {
                let mut q = p.clone();
                q[i] ^= x;
                let mut d = StreamDecoder::new(s.header.clone());
                if d.apply_step(&q).is_ok() {
                    let _ = (d.mesh(), d.heights_m());
                } else {
                    assert!(d.steps().is_empty());
                }
            }
        }
    }
}
