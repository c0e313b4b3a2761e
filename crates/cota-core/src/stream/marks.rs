//! Streaming criterion-driven refinements with fictitious points, coarse to
//! fine: only the selected points' heights travel; fictitious points cost one
//! flag.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2.2 (fictitious points: needed only to
//! complete the hierarchy, height interpolated on their diagonal) and §3
//! ("Transmisión progresiva": the coarse mesh first, then the points each finer
//! tolerance adds; fictitious points are never sent, the receiver adds them
//! itself). The input is a sequence of closed [`Marks`] of
//! [`crate::refine`] in one [`Mode`], each containing the previous one.
//!
//! # Steps
//! 1. **Schedule** ([`encode_marks_progressive`], the vertical-error
//!    criterion): step 0 is the border's points only (the coarsest mesh the
//!    grid allows, tolerance `f32::MAX`); then tolerances `T_1 > T_2 > …`:
//!    powers of two from the step-0 mesh's error down to `quantum_m`, then
//!    the requested `max_error_m` (or the caller's thresholds, as in
//!    [`super`]). Step `k`'s marks are the refinement at `T_k`
//!    continued from step `k − 1`'s closed marks
//!    ([`crate::refine::refine_marks_from`]): the previous selection plus the
//!    points the refinement at `T_k` adds, closed with [`Marks::close`]. So
//!    steps are nested (a step only adds points and splits) and every leaf of
//!    step `k`'s mesh meets `T_k` with its actual heights. Other criteria:
//!    build the nested marks yourself and call [`encode_marks_steps`].
//! 2. **Walk** (each step) the tree from the roots as `refine::triangulate`
//!    does: straddling triangles split without a bit; an inside non-unit
//!    triangle already split in the previous step splits without a bit; every
//!    other one codes "this side of my split point splits now" (adaptive, per
//!    level, whether the point is already present and, after step 0, whether
//!    the triangle is new in this step).
//! 3. **Points.** The first time a step's walk meets a split point: if it is
//!    new, one bit (per level) says whether it is *selected* (real height) or
//!    *fictitious*; if it was fictitious in the previous step, one bit says
//!    whether it becomes selected now; a point already selected costs nothing.
//!    A point that becomes selected sends its quantised height as a residual
//!    against `round(((z_a + z_b) / 2) / quantum)` (its diagonal's midpoint,
//!    with fictitious ends at their interpolated height); a fictitious point
//!    sends nothing. Split points of straddling triangles inside the grid are
//!    the border's selected points: height in step 0, no flag.
//! 4. **Receiver.** It adds the step's selected points to the previous closed
//!    marks (step 0: the border's), closes them (`Marks::select`, `close`: the
//!    closure of a selection is unique, so it equals the sender's; the walk's
//!    present and selected points must agree with it, else the step is
//!    rejected), and triangulates with the decoded heights. A point fictitious
//!    in step `k − 1` and selected in step `k` takes its real height from step
//!    `k` on: earlier meshes are not changed (the receiver holds them as they
//!    were), later ones interpolate their fictitious points from it, exactly as
//!    the sender's `triangulate` does. The mesh after every step equals the
//!    sender's step mesh vertex for vertex.
//! 5. **Stated error.** The sender measures the step mesh exactly against the
//!    quantised grid ([`crate::measure`], every sample, the semantics of
//!    [`crate::check_mesh`], also for the faithful mode's hanging vertices) and
//!    states it rounded up to `f32`: a true bound of that prefix's mesh, at most
//!    `T_k` for the vertical-error schedule. The stated errors of successive
//!    steps need not decrease (a refinement may raise the error at a sample
//!    slightly), although they do in practice.
//!
//! # Bit layout
//! Header kind 1 (conforming), 2 (fictitious, watertight) or 3 (fictitious,
//! faithful) of [`super`]. Each step: `max_error_m: f32` (the stated
//! bound), then one range-coded block: in walk order, `split: bit` per inside
//! candidate triangle, then for a split point met for the first time in the
//! step `selected: bit` (new point) or `promoted: bit` (fictitious before)
//! and, when the point becomes selected (or is a border point in step 0), its
//! residual ([`super::coder::ResidualModel`], one model per level and
//! step; steps above 15 share step 15's). Step 0 uses its own contexts and is
//! exactly the former one-step layout, so one-step files still decode.

use super::format::{
    lattice, quantize, thresholds, EncodedStep, EncodedStream, StreamError, StreamHeader,
    StreamKind, StreamOptions, MAX_Q, UNKNOWN,
};
use super::models::{level, residual_ctx, Models, Question};
use super::state::{predict, Answers, Coder, Decoder, Encoder, State};
use crate::bitree::round_up_f32;
use crate::criteria::MaxVerticalError;
use crate::grid::{GeoRef, HeightGrid};
use crate::hierarchy::{walk, Hierarchy, Pt, Tri, Visitor};
use crate::mesh::metrics::measure;
use crate::mesh::Mesh;
use crate::progress::{Counter, Progress, Stages};
use crate::refine::{refine_marks_from, triangulate, Marks, Mode, RefineOptions};

/// Per-sample flags of the walk: selected (in this step's marks).
const SEL: u8 = 1;
/// Split bits of the two sides of a diamond (coded in this step).
const SIDES: [u8; 2] = [2, 4];
/// The point was met in this step's walk.
const SEEN: u8 = 8;

/// Which side of `m`'s diamond the triangle with apex `c` lies on.
#[inline]
fn side(c: Pt, m: Pt) -> usize {
    usize::from((c[1], c[0]) >= (m[1], m[0]))
}

/// The walk of one step: [`Walk`] with its coder.
struct StepWalk<'w, 's, C> {
    w: &'w mut Walk<'s>,
    c: &'w mut C,
}

impl<C: Coder> Visitor for StepWalk<'_, '_, C> {
    /// Whether the triangle is new in this step (its parent was not split
    /// in the previous one).
    type Down = bool;
    type Error = String;

    fn straddling(&mut self, t: &Tri, _new_tri: bool) -> Result<bool, String> {
        self.w.straddling(self.c, t)?;
        Ok(false)
    }

    fn inside(&mut self, t: &Tri, new_tri: bool) -> Result<Option<bool>, String> {
        self.w.inside(self.c, t, new_tri)
    }
}

/// The sender's answers: the step's closed marks.
impl Answers for &Marks {
    fn answer(&mut self, q: Question, t: &Tri, _i: usize) -> bool {
        match q {
            Question::Split(_) | Question::Side(_) => self.splits(t),
            Question::Selected(_) | Question::Promoted(_) => self.is_selected(t.mid()),
        }
    }
}

/// One step's walk: flags, prediction heights, and the previous step's marks.
struct Walk<'s> {
    hier: Hierarchy,
    q: &'s mut [i64],
    /// The previous step's closed marks (`None` in step 0).
    prev: Option<&'s Marks>,
    step: usize,
    flags: Vec<u8>,
    z: Vec<f64>,
    quantum_m: f64,
}

impl<'s> Walk<'s> {
    fn new(
        hier: Hierarchy,
        q: &'s mut [i64],
        prev: Option<&'s Marks>,
        step: usize,
        quantum_m: f64,
    ) -> Walk<'s> {
        let z = q
            .iter()
            .map(|&v| {
                if v == UNKNOWN {
                    f64::NAN
                } else {
                    v as f64 * quantum_m
                }
            })
            .collect();
        let w = hier.width();
        let flags = match prev {
            None => vec![0; q.len()],
            Some(m) => (0..q.len() as u32)
                .map(|i| {
                    if m.is_selected([i % w, i / w]) {
                        SEL
                    } else {
                        0
                    }
                })
                .collect(),
        };
        Walk {
            hier,
            q,
            prev,
            step,
            flags,
            z,
            quantum_m,
        }
    }

    fn z_at(&self, p: Pt) -> Option<f64> {
        if !self.hier.contains(p) {
            return None;
        }
        let v = self.z[self.hier.index(p)];
        (!v.is_nan()).then_some(v)
    }

    fn learn<C: Coder>(&mut self, c: &mut C, t: &Tri, i: usize) -> Result<(), String> {
        let pred = (predict(t, |p| self.z_at(p)) / self.quantum_m).round();
        let pred = if pred.abs() < MAX_Q as f64 {
            pred as i64
        } else {
            0
        };
        let q = c.height(residual_ctx(level(t), self.step), i, pred)?;
        self.q[i] = q;
        self.z[i] = q as f64 * self.quantum_m;
        Ok(())
    }

    fn interpolate(&mut self, t: &Tri, i: usize) -> Result<(), String> {
        match (self.z_at(t.a), self.z_at(t.b)) {
            (Some(a), Some(b)) => {
                self.z[i] = 0.5 * (a + b);
                Ok(())
            }
            _ => Err("a fictitious point with both diagonal ends known".into()),
        }
    }

    /// Walks this step's tree (see the module docs), coding through `c`.
    fn run<C: Coder>(&mut self, c: &mut C) -> Result<(), String> {
        let hier = self.hier;
        walk(&hier, &hier.roots(), true, &mut StepWalk { w: self, c })
    }

    /// A straddling triangle: its split point inside the grid is a border
    /// point, selected, its height sent in step 0.
    fn straddling<C: Coder>(&mut self, c: &mut C, t: &Tri) -> Result<(), String> {
        let m = t.mid();
        if self.hier.contains(m) {
            let i = self.hier.index(m);
            self.flags[i] |= SEEN;
            if self.flags[i] & SEL == 0 {
                self.flags[i] |= SEL;
                if self.q[i] == UNKNOWN {
                    self.learn(c, t, i)?;
                }
            }
        }
        Ok(())
    }

    /// An inside triangle (`new_tri`: its parent was not split in the
    /// previous step): whether it splits, and what its split point is the
    /// first time the step meets it. `Some(children's new_tri)` when it splits.
    fn inside<C: Coder>(
        &mut self,
        c: &mut C,
        t: &Tri,
        new_tri: bool,
    ) -> Result<Option<bool>, String> {
        let m = t.mid();
        let i = self.hier.index(m);
        let lvl = level(t);
        let (prev_split, prev_present, prev_selected) = match self.prev {
            Some(p) => (p.splits(t), p.is_present(m), p.is_selected(m)),
            None => (false, false, false),
        };
        if !prev_split {
            let present = usize::from(prev_present || self.flags[i] & !SEEN != 0);
            let ctx = if self.step == 0 {
                lvl * 2 + present
            } else {
                (lvl * 2 + present) * 2 + usize::from(new_tri)
            };
            if !c.bit(Question::Side(ctx), self.step, t, i)? {
                return Ok(None);
            }
            self.flags[i] |= SIDES[side(t.c, m)];
        }
        if self.flags[i] & SEEN == 0 {
            self.flags[i] |= SEEN;
            if !prev_selected {
                let question = if prev_present {
                    Question::Promoted(lvl)
                } else {
                    Question::Selected(lvl)
                };
                if c.bit(question, self.step, t, i)? {
                    self.flags[i] |= SEL;
                    self.learn(c, t, i)?;
                } else {
                    self.interpolate(t, i)?;
                }
            }
        }
        Ok(Some(!prev_split))
    }

    /// The closed marks the receiver derives: the previous step's (or the
    /// border's) plus this step's selected points, closed. Fails when the
    /// walk's present or selected points disagree with them.
    fn derive(&self, mode: Mode) -> Result<Marks, String> {
        let hier = self.hier;
        let mut marks = match self.prev {
            Some(p) => p.clone(),
            None => {
                let mut m = Marks::new(hier, mode);
                m.seed_border();
                m
            }
        };
        let w = hier.width();
        for (i, &f) in self.flags.iter().enumerate() {
            if f & SEL != 0 {
                marks.select([i as u32 % w, i as u32 / w]);
            }
        }
        marks.close();
        for (i, &f) in self.flags.iter().enumerate() {
            let p = [i as u32 % w, i as u32 / w];
            let was = self.prev.is_some_and(|m| m.is_present(p));
            let walked = was || f & (SEL | SIDES[0] | SIDES[1]) != 0;
            if marks.is_selected(p) != (f & SEL != 0) || marks.is_present(p) != walked {
                return Err(format!(
                    "marks closed under the {} rule, but the point at column {}, row {} is {} in the step and {} after closure",
                    mode.name(),
                    p[0],
                    p[1],
                    describe(f & SEL != 0, walked),
                    describe(marks.is_selected(p), marks.is_present(p)),
                ));
            }
        }
        Ok(marks)
    }
}

fn describe(selected: bool, present: bool) -> &'static str {
    match (selected, present) {
        (true, _) => "selected",
        (false, true) => "fictitious",
        (false, false) => "absent",
    }
}

/// The mesh of closed `marks` with heights `q · quantum_m` (0 where unknown:
/// only fictitious or absent samples, never read).
fn mesh_of(
    hier: &Hierarchy,
    q: &[i64],
    quantum_m: f64,
    marks: &Marks,
    mode: Mode,
) -> Result<Mesh, String> {
    let heights: Vec<f32> = q
        .iter()
        .map(|&v| {
            if v == UNKNOWN {
                0.0
            } else {
                (v as f64 * quantum_m) as f32
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
    Ok(triangulate(&grid, marks, mode).mesh)
}

/// Encodes one closed `marks` of a refinement of `grid` in `mode` as a
/// one-step stream (see [`encode_marks_steps`]). Heights are quantised with
/// `opts.quantum_m` (`opts.max_error_m` and thresholds are ignored); the step
/// states the mesh's exact max error against the quantised grid.
///
/// # Errors
/// As [`encode_marks_steps`].
pub fn encode_marks(
    grid: &HeightGrid,
    marks: &Marks,
    mode: Mode,
    opts: &StreamOptions,
) -> Result<EncodedStream, StreamError> {
    encode_marks_steps(grid, &[(f64::from(f32::MAX), marks.clone())], mode, opts)
}

/// Encodes a progressive marks stream of `grid` in `mode` under the
/// vertical-error criterion: step 0 the border's points, then the refinement
/// at each tolerance of the schedule (module docs), down to
/// `opts.max_error_m` (or `opts.thresholds_m`, then `opts.max_error_m`).
/// Refines the quantised grid, so every stated error is exact for it.
///
/// # Errors
/// [`StreamError::BadQuantum`], [`StreamError::BadMaxError`],
/// [`StreamError::HeightOutOfRange`], or [`StreamError::Mesh`] for grids that
/// cannot be meshed.
pub fn encode_marks_progressive(
    grid: &HeightGrid,
    mode: Mode,
    opts: &StreamOptions,
) -> Result<EncodedStream, StreamError> {
    encode_marks_progressive_with_progress(grid, mode, opts, crate::progress::NONE)
}

/// [`encode_marks_progressive`], telling `progress(done, total)` as it
/// goes: each tolerance refined, then the steps encoded, weighted by their
/// share of the time (in thousandths, [`crate::progress`]).
///
/// # Errors
/// As [`encode_marks_progressive`].
pub fn encode_marks_progressive_with_progress(
    grid: &HeightGrid,
    mode: Mode,
    opts: &StreamOptions,
    progress: Progress<'_>,
) -> Result<EncodedStream, StreamError> {
    let e_last = opts.max_error_m;
    if e_last.is_nan() || e_last < 0.0 {
        return Err(StreamError::BadMaxError(e_last));
    }
    let (qgrid, _) = quantize(grid, opts.quantum_m)?;
    let hier = crate::error::hierarchy_for(&qgrid)?;
    let mut marks = Marks::new(hier, mode);
    marks.seed_border();
    let coarse = triangulate(&qgrid, &marks, mode).mesh;
    let emax = measure(&qgrid, &coarse).max_error_m;
    let refine_opts = RefineOptions::DEFAULT.with_mode(mode);
    let mut steps = vec![(f64::from(f32::MAX), marks.clone())];
    // The refinements, then the encoding: about half each.
    let stages = Stages::new(progress, &[1, 1]);
    let tolerances = thresholds(opts, emax, f64::INFINITY);
    let first = stages.stage(0);
    let refined = Counter::new(&first, tolerances.len());
    for t in tolerances {
        let crit = MaxVerticalError { max_error_m: t };
        let (_, next) = refine_marks_from(&qgrid, &crit, &refine_opts, marks)?;
        marks = next.clone();
        steps.push((t, next));
        refined.add(1);
    }
    stages.finish(0);
    let encoded = encode_marks_steps_with(grid, &steps, mode, opts, &stages.stage(1));
    stages.finish(1);
    encoded
}

/// Encodes nested closed marks of refinements of `grid` in `mode`, coarse to
/// fine, each with a label (its tolerance in metres, reported as
/// [`EncodedStep::threshold_m`]). Heights are quantised with
/// `opts.quantum_m` (`opts.max_error_m` and thresholds are ignored); each step
/// states its mesh's exact max error against the quantised grid.
///
/// # Errors
/// [`StreamError::BadQuantum`], [`StreamError::HeightOutOfRange`],
/// [`StreamError::BadHeader`] when some marks were made for another grid
/// size, and [`StreamError::BadStep`] when there is no step, or a step's marks
/// are not closed under `mode`'s rule, or do not contain the previous step's.
pub fn encode_marks_steps(
    grid: &HeightGrid,
    steps: &[(f64, Marks)],
    mode: Mode,
    opts: &StreamOptions,
) -> Result<EncodedStream, StreamError> {
    encode_marks_steps_with(grid, steps, mode, opts, crate::progress::NONE)
}

/// [`encode_marks_steps`], telling `progress(steps_done, steps)`.
fn encode_marks_steps_with(
    grid: &HeightGrid,
    steps: &[(f64, Marks)],
    mode: Mode,
    opts: &StreamOptions,
    progress: Progress<'_>,
) -> Result<EncodedStream, StreamError> {
    let (qgrid, lattice_exact) = quantize(grid, opts.quantum_m)?;
    let Some((_, first)) = steps.first() else {
        return Err(StreamError::BadStep {
            step: 0,
            expected: "at least one step of marks".into(),
            found: "none".into(),
        });
    };
    let hier = *first.hierarchy();
    for (_, m) in steps {
        let h = m.hierarchy();
        if (h.width() as usize, h.height() as usize) != (grid.width(), grid.height()) {
            return Err(StreamError::BadHeader {
                expected: format!("marks for the {}x{} grid", grid.width(), grid.height()),
                found: format!("marks for {}x{}", h.width(), h.height()),
            });
        }
    }
    let q = lattice(&qgrid, opts.quantum_m);
    let header = StreamHeader::new(&hier, opts.quantum_m, &q, StreamKind::Marks(mode));
    let mut enc = StepEncoder {
        state: State::new(&header),
        models: Models::new(),
        qgrid: &qgrid,
        q: &q,
        quantum_m: opts.quantum_m,
        mode,
    };
    let mut prev: Option<Marks> = None;
    let mut out = Vec::with_capacity(steps.len());
    for (k, (label, marks)) in steps.iter().enumerate() {
        let Step {
            block,
            derived,
            mesh,
            new_points,
        } = enc
            .step(prev.as_ref(), k, marks)
            .map_err(|(expected, found)| StreamError::BadStep {
                step: k,
                expected,
                found,
            })?;
        let stated = round_up_f32(measure(&qgrid, &mesh).max_error_m);
        let mut payload = stated.to_le_bytes().to_vec();
        payload.extend_from_slice(&block);
        out.push(EncodedStep {
            threshold_m: *label,
            max_error_m: stated as f64,
            payload,
            triangles: mesh.triangle_count(),
            vertices: mesh.vertex_count(),
            new_points,
        });
        prev = Some(derived);
        progress(k + 1, steps.len());
    }
    Ok(EncodedStream {
        header,
        steps: out,
        lattice_exact,
    })
}

/// One encoded step of a marks stream.
struct Step {
    /// The range-coded block.
    block: Vec<u8>,
    /// The closed marks the receiver derives (equal to the step's).
    derived: Marks,
    /// The step's mesh.
    mesh: Mesh,
    /// Heights sent.
    new_points: usize,
}

/// Why a step cannot be encoded: what was expected, what was found.
type Refusal = (String, String);

/// The sender of a marks stream between steps.
struct StepEncoder<'g> {
    state: State,
    models: Models,
    /// The quantised grid and its heights in quanta.
    qgrid: &'g HeightGrid,
    q: &'g [i64],
    quantum_m: f64,
    mode: Mode,
}

impl StepEncoder<'_> {
    /// Step `k` of `marks` after `prev`: its coded block, the marks the
    /// receiver derives, the step's mesh and the heights sent. Fails with
    /// `(expected, found)`.
    fn step(&mut self, prev: Option<&Marks>, k: usize, marks: &Marks) -> Result<Step, Refusal> {
        let closed_rule = || format!("marks closed under the {} rule", self.mode.name());
        if marks.mode() != self.mode {
            return Err((
                closed_rule(),
                format!("marks closed under the {} rule", marks.mode().name()),
            ));
        }
        if prev.is_some_and(|p| !marks.contains(p)) {
            return Err((
                "marks containing the previous step's".into(),
                "marks that drop a point or a split".into(),
            ));
        }
        let mut c = Encoder::new(&mut self.models, marks, self.q);
        let mut walk = Walk::new(self.state.hier, &mut self.state.q, prev, k, self.quantum_m);
        walk.run(&mut c)
            .map_err(|found| ("marks the encoder can walk".into(), found))?;
        let derived = walk
            .derive(self.mode)
            .map_err(|found| ("closed marks".into(), found))?;
        if derived != *marks {
            return Err((closed_rule(), "marks that their closure changes".into()));
        }
        let mesh = triangulate(self.qgrid, marks, self.mode).mesh;
        Ok(Step {
            new_points: c.new_points,
            block: c.enc.finish(),
            derived,
            mesh,
        })
    }
}

/// Decodes one step of a marks stream into `st` (whose `marks` are the
/// previous step's); returns the step's mesh and the number of heights read.
/// On error `st` is unchanged.
pub(super) fn decode_step(
    st: &mut State,
    models: &mut Models,
    header: &StreamHeader,
    mode: Mode,
    step: usize,
    block: &[u8],
) -> Result<(Mesh, usize), String> {
    let mut c = Decoder::new(models, block);
    let hier = st.hier;
    let mut q = st.q.clone();
    let mut w = Walk::new(hier, &mut q, st.marks.as_ref(), step, header.quantum_m);
    w.run(&mut c)?;
    if c.dec.overrun() > 0 {
        return Err(format!(
            "{} bytes of coded data, found {} (truncated or corrupted)",
            block.len() + c.dec.overrun(),
            block.len()
        ));
    }
    let marks = w.derive(mode)?;
    let mesh = mesh_of(&hier, &q, header.quantum_m, &marks, mode)?;
    st.q = q;
    st.marks = Some(marks);
    Ok((mesh, c.new_points))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, reason = "tests")]
mod test {
    use super::*;
    use crate::bitree::round_up_f32 as stated_f32;
    use crate::refine::refine_marks;
    use crate::stream::StreamDecoder;
    use crate::{check_mesh, CheckOptions};

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

    const MODES: [Mode; 3] = [
        Mode::Conforming,
        Mode::Fictitious { watertight: true },
        Mode::Fictitious { watertight: false },
    ];

    fn check_options(mode: Mode, e: f64) -> CheckOptions {
        CheckOptions::conforming(e)
            .with_conforming(mode.is_conforming())
            .with_allow_fictitious(!matches!(mode, Mode::Conforming))
    }

    #[test]
    fn one_step_streams_rebuild_the_refined_mesh() {
        for (w, h) in [(33, 33), (45, 29)] {
            let g = grid(w, h);
            for mode in MODES {
                for e in [0.0, 2.0, 10.0] {
                    let crit = MaxVerticalError { max_error_m: e };
                    let opts = RefineOptions::DEFAULT.with_mode(mode);
                    let (r, marks) = refine_marks(&g, &crit, &opts).unwrap();
                    let s = encode_marks(&g, &marks, mode, &StreamOptions::default()).unwrap();
                    assert_eq!(s.steps.len(), 1);
                    assert!(s.steps[0].max_error_m <= e);
                    let hb = StreamHeader::from_bytes(&s.header.to_bytes()).unwrap();
                    let mut d = StreamDecoder::new(hb);
                    d.apply_step(&s.steps[0].payload).unwrap();
                    let mesh = d.mesh();
                    assert_eq!(mesh, r.mesh, "{w}x{h} {mode:?} {e}");
                    assert!(s.steps[0].new_points <= r.transmitted_points);
                    check_mesh(&g, &mesh, &check_options(mode, e)).unwrap();
                    assert!(d.heights_m().unwrap().iter().all(|z| z.is_finite()));
                }
            }
        }
    }

    #[test]
    fn every_prefix_of_a_progressive_stream_is_the_senders_mesh() {
        for (w, h) in [(33, 33), (45, 29)] {
            let g = grid(w, h);
            for mode in MODES {
                let o = StreamOptions::default().with_max_error_m(1.0);
                let s = encode_marks_progressive(&g, mode, &o).unwrap();
                assert!(s.steps.len() >= 4, "{}", s.steps.len());
                let hb = StreamHeader::from_bytes(&s.header.to_bytes()).unwrap();
                let mut d = StreamDecoder::new(hb);
                let mut prev_tris = 0;
                for (k, step) in s.steps.iter().enumerate() {
                    let info = d.apply_step(&step.payload).unwrap();
                    let mesh = d.mesh();
                    assert_eq!(info.triangles, step.triangles);
                    assert!(step.triangles >= prev_tris, "{mode:?} step {k}");
                    prev_tris = step.triangles;
                    if k > 0 {
                        assert!(step.max_error_m <= step.threshold_m, "{mode:?} step {k}");
                    }
                    let r = check_mesh(&g, &mesh, &check_options(mode, step.max_error_m)).unwrap();
                    // The stated error is the exact one, rounded up to f32.
                    assert_eq!(stated_f32(r.metrics.max_error_m) as f64, step.max_error_m);
                }
                // The last step is the refinement at 1 m continued from the others.
                assert!(s.steps.last().unwrap().max_error_m <= 1.0);
            }
        }
    }

    #[test]
    fn unnested_or_unclosed_marks_are_refused() {
        let g = grid(33, 33);
        let mode = Mode::Fictitious { watertight: true };
        let opts = RefineOptions::DEFAULT.with_mode(mode);
        let fine = refine_marks(&g, &MaxVerticalError { max_error_m: 1.0 }, &opts)
            .unwrap()
            .1;
        let coarse = refine_marks(&g, &MaxVerticalError { max_error_m: 8.0 }, &opts)
            .unwrap()
            .1;
        let so = StreamOptions::default();
        let e = encode_marks_steps(&g, &[(8.0, fine.clone()), (1.0, coarse)], mode, &so);
        assert!(
            matches!(e, Err(StreamError::BadStep { step: 1, .. })),
            "{e:?}"
        );
        let e = encode_marks_steps(&g, &[(1.0, fine.clone())], Mode::Conforming, &so);
        assert!(
            matches!(e, Err(StreamError::BadStep { step: 0, .. })),
            "{e:?}"
        );
        let mut open = Marks::new(*fine.hierarchy(), mode);
        open.seed_border();
        assert!(open.select([1, 2]));
        let e = encode_marks_steps(&g, &[(1.0, open)], mode, &so);
        assert!(matches!(e, Err(StreamError::BadStep { .. })), "{e:?}");
        assert!(encode_marks_steps(&g, &[], mode, &so).is_err());
    }

    #[test]
    fn corrupted_marks_payloads_never_panic_and_roll_back() {
        let g = grid(21, 17);
        let mode = Mode::Fictitious { watertight: false };
        let o = StreamOptions::default().with_max_error_m(2.0);
        let s = encode_marks_progressive(&g, mode, &o).unwrap();
        assert!(s.steps.len() >= 3);
        let k = 2;
        let mut good = StreamDecoder::new(s.header.clone());
        for st in &s.steps[..k] {
            good.apply_step(&st.payload).unwrap();
        }
        let p = &s.steps[k].payload;
        for i in 4..p.len() {
            for x in [1u8, 0x80] {
                let mut q = p.clone();
                q[i] ^= x;
                let mut d = good.clone();
                if d.apply_step(&q).is_ok() {
                    let _ = (d.mesh(), d.heights_m());
                } else {
                    assert_eq!(d.steps().len(), k);
                    assert_eq!(d.mesh(), good.mesh());
                    // The good step still applies after a rolled-back bad one.
                    d.apply_step(p).unwrap();
                }
            }
        }
    }
}
