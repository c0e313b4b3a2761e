//! Criterion-driven refinement of the bitree, conforming or with fictitious
//! points.
//!
//! Papers `001_49f2c365e8c41172.txt` (refine the frontier: a frontier triangle
//! that satisfies the indicator stays, otherwise it splits, with chains of
//! forced splits for conformity) and `000_ebf7e3a88dffd361.txt` §2.2
//! (fictitious points, see [`marks`]). A criterion is neither
//! monotone nor shared by the two triangles of a diamond, so unlike
//! [`crate::Bitree::extract`] this path needs the dependency closure.
//!
//! 1. Select the border's split points ([`Marks::seed_border`]).
//! 2. Close the selection ([`Marks::close`]) under the mode's rule.
//! 3. Walk the tree from the roots, splitting straddling triangles and inside
//!    ones whose side is marked; on the way down give every present point its
//!    mesh height: the sample's for a selected point, the midpoint
//!    interpolation of its diagonal's two ends (already known, they are
//!    vertices of an ancestor) for a fictitious one, rounded to `f32`.
//! 4. For every leaf, build its [`crate::criteria::Element`] from its **actual** vertex heights,
//!    with `vertical_error_m` the exact largest `|plane − h|` over every sample
//!    in or on it (the plane through the mesh's own `f32` heights, as
//!    [`crate::measure`] and the checker compute it), and ask the criterion.
//!    A leaf that wants a split gets its split point selected (unless it is a
//!    unit triangle). A fictitious vertex `v` of such a leaf (unit or not) is
//!    selected too when the deviation `|z_v − h_v|` alone makes the criterion
//!    want a split while a zero error would not (the vertex is then the cause,
//!    and no split can remove it). So the points "selected by the criterion"
//!    are the split points of the leaves it refined; fictitious points are
//!    those only the dependencies (forced splits) needed.
//! 5. Repeat 2–4 until no point is added; then emit the leaves (numbered
//!    row-major as in [`crate::bitree::extract`]).
//!
//! # The bound with fictitious points
//! Fictitious points change the planes of the triangles that use them, so the
//! error of a triangle cannot be read from the bitree's error map. The loop
//! above evaluates every final leaf with its actual heights: at the fixed point
//! every leaf satisfies the criterion, or is a unit triangle whose vertices the
//! criterion does not want changed. For [`crate::MaxVerticalError`]`(E)` this
//! means every leaf has exact error `≤ E` (a unit leaf's only samples are its
//! vertices, and a vertex deviating by more than `E` is promoted by rule 4), so
//! the bound holds at every sample, measured with the mesh's heights. A hanging
//! vertex (faithful mode) is a sample on the unsplit neighbour's edge too, and
//! that neighbour is evaluated like any leaf. The loop ends because every round
//! selects at least one new point.
//!
//! # Runtime
//! Each round walks the mesh and evaluates every leaf not accepted before with
//! the same vertex heights (a cache keyed by the leaf and its heights), in
//! parallel; about `2·log2(N)` rounds (15 on a 1201² SRTM tile, 0.2–0.8 s
//! for 5 m to 0 m in fictitious mode). Memory: two bytes and two `f32` per
//! sample (the marks, the accepted leaves, this round's heights and the
//! last's), plus the leaves and the points the rejected ones select.

mod judge;
mod leaves;
pub mod marks;
mod mode;

use rayon::prelude::*;

use crate::criteria::Criterion;
use crate::error::MeshError;
use crate::grid::HeightGrid;
use crate::hierarchy::Pt;
use crate::mesh::Mesh;
use judge::{judge, unpack, Accepted, Picks};
use leaves::{emit, leaves};

pub use marks::Marks;
pub use mode::Mode;

/// Options for [`refine`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct RefineOptions {
    /// Conforming or fictitious. Default: [`Mode::Conforming`].
    pub mode: Mode,
}

impl RefineOptions {
    /// The defaults: conforming.
    pub const DEFAULT: RefineOptions = RefineOptions {
        mode: Mode::Conforming,
    };

    /// Options with the given mode.
    pub const fn with_mode(mut self, mode: Mode) -> Self {
        self.mode = mode;
        self
    }
}

/// A refined mesh and its point counts.
#[derive(Debug, Clone)]
pub struct Refined {
    /// The mesh. Fictitious vertices carry their interpolated height.
    pub mesh: Mesh,
    /// The mode used.
    pub mode: Mode,
    /// Vertices with their sample's real height: the points a progressive
    /// transmission sends (paper 000).
    pub transmitted_points: usize,
    /// Vertices with an interpolated height (never transmitted).
    pub fictitious_points: usize,
    /// Hanging vertices of the faithful variant, each closed by one degenerate
    /// "line triangle" in paper 000's strips (0 in the other modes).
    pub line_triangles: usize,
    /// Rounds of the refinement loop.
    pub rounds: usize,
}

/// Refines the bitree over `grid` with `criterion` (see the module docs).
///
/// ```
/// use cota_core::{GeoRef, HeightGrid, MaxVerticalError, check_mesh, CheckOptions};
/// use cota_core::refine::{refine, Mode, RefineOptions};
/// let (w, h) = (33, 21);
/// let heights: Vec<f32> = (0..w * h)
///     .map(|i| ((i % w) as f32 * 0.4).sin() * 20.0 + ((i / w) as f32 * 0.3).cos() * 15.0)
///     .collect();
/// let grid = HeightGrid::new(w, h, heights, GeoRef::unreferenced(30.0)).unwrap();
/// let crit = MaxVerticalError { max_error_m: 1.0 };
/// let opts = RefineOptions::DEFAULT.with_mode(Mode::Fictitious { watertight: true });
/// let r = refine(&grid, &crit, &opts).unwrap();
/// let check = CheckOptions::conforming(1.0).with_allow_fictitious(true);
/// assert!(check_mesh(&grid, &r.mesh, &check).is_ok());
/// ```
///
/// # Errors
/// [`MeshError::GridTooSmall`], [`MeshError::GridTooLarge`] or
/// [`MeshError::Voids`].
pub fn refine(
    grid: &HeightGrid,
    criterion: &dyn Criterion,
    opts: &RefineOptions,
) -> Result<Refined, MeshError> {
    refine_marks(grid, criterion, opts).map(|(r, _)| r)
}

/// [`refine`], also returning the closed [`Marks`] it ended with (which points
/// are selected, which fictitious), e.g. to stream them
/// ([`crate::stream::encode_marks`]).
///
/// # Errors
/// As [`refine`].
pub fn refine_marks(
    grid: &HeightGrid,
    criterion: &dyn Criterion,
    opts: &RefineOptions,
) -> Result<(Refined, Marks), MeshError> {
    let hier = crate::error::hierarchy_for(grid)?;
    let mut marks = Marks::new(hier, opts.mode);
    marks.seed_border();
    refine_marks_from(grid, criterion, opts, marks)
}

/// [`refine_marks`] continued from `marks`, closed marks of an earlier
/// refinement of the same `grid` in the same mode (e.g. at a larger
/// tolerance): points are only added, so the result's selection contains
/// `marks`' selection, and at the fixed point every leaf meets `criterion`
/// with its actual heights, as in [`refine`]. The progressive marks streams
/// ([`crate::stream::encode_marks_progressive`]) build their nested steps this way.
///
/// # Errors
/// As [`refine`], and [`MeshError::MarksSizeMismatch`] for marks made for a
/// grid of another size.
pub fn refine_marks_from(
    grid: &HeightGrid,
    criterion: &dyn Criterion,
    opts: &RefineOptions,
    marks: Marks,
) -> Result<(Refined, Marks), MeshError> {
    let hier = crate::error::hierarchy_for(grid)?;
    let mut marks = marks;
    if *marks.hierarchy() != hier {
        let m = marks.hierarchy();
        return Err(MeshError::MarksSizeMismatch {
            width: grid.width(),
            height: grid.height(),
            marks_width: m.width() as usize,
            marks_height: m.height() as usize,
        });
    }
    marks.close();
    let mut accepted = Accepted::new(grid.len());
    let mut z_before: Option<Vec<f32>> = None;
    let mut rounds = 0;
    loop {
        rounds += 1;
        let (mut fresh, z) = leaves(grid, &marks);
        // A leaf accepted in an earlier round whose vertices kept their
        // heights since is not judged again; one whose heights changed is
        // forgotten (its verdict may change).
        let kept = |p: Pt| {
            let i = hier.index(p);
            z_before
                .as_ref()
                .is_some_and(|b| b[i].to_bits() == z[i].to_bits())
        };
        fresh.retain(|l| {
            let same = kept(l.tri.a) && kept(l.tri.b) && kept(l.tri.c);
            if same && accepted.holds(l, &hier) {
                return false;
            }
            accepted.set(l, &hier, false);
            true
        });
        let picks: Vec<(u32, Picks)> = fresh
            .par_iter()
            .enumerate()
            .filter_map(|(k, l)| {
                let p = judge(grid, &marks, &z, l, criterion).picks()?;
                Some((k as u32, p))
            })
            .collect();
        let mut added = false;
        let mut next = picks.iter().peekable();
        for (k, l) in fresh.iter().enumerate() {
            match next.next_if(|(at, _)| *at as usize == k) {
                None => accepted.set(l, &hier, true),
                Some(&(_, p)) => {
                    for point in unpack(p) {
                        added |= marks.select(point);
                    }
                }
            }
        }
        if !added {
            break;
        }
        drop((fresh, picks));
        marks.close();
        z_before = Some(z);
    }
    let mut out = triangulate(grid, &marks, opts.mode);
    out.rounds = rounds;
    Ok((out, marks))
}

/// The mesh a closed set of marks describes (steps 3 and 5 of the module
/// docs), for callers that select points themselves: `grid` must be the one
/// `marks` was made for, with no voids, and `mode` is only recorded.
/// `rounds` is 0.
pub fn triangulate(grid: &HeightGrid, marks: &Marks, mode: Mode) -> Refined {
    let (leaves, z) = leaves(grid, marks);
    let (mesh, transmitted, fictitious) = emit(grid, marks, &z, leaves);
    Refined {
        mesh,
        mode,
        transmitted_points: transmitted,
        fictitious_points: fictitious,
        line_triangles: marks.hanging_vertices(),
        rounds: 0,
    }
}
