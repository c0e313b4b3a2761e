//! Criterion-driven refinement of the bitree, conforming or with fictitious
//! points.
//!
//! Papers `001_49f2c365e8c41172.txt` (refine the frontier: a frontier triangle
//! that satisfies the indicator stays, otherwise it splits, with chains of
//! forced splits for conformity) and `000_ebf7e3a88dffd361.txt` §2.2
//! (fictitious points, see [`crate::fictitious`]). A criterion is neither
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
//! 4. For every leaf, build its [`Element`] from its **actual** vertex heights,
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
//! for 5 m to 0 m in fictitious mode). Memory: one byte and one `f32` per
//! sample, plus the leaves and the cache.

use std::collections::HashSet;

use rayon::prelude::*;

use crate::criteria::{Criterion, Element};
use crate::error::MeshError;
use crate::fictitious::{Closure, Marks};
use crate::grid::HeightGrid;
use crate::hierarchy::{orient_up, Hierarchy, Placement, Pt, Tri};
use crate::mesh::raster::max_deviation;
use crate::mesh::{Mesh, MeshVertex};

/// How points needed only for the hierarchy are treated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// Every vertex carries its sample's real height; forced splits keep the
    /// mesh conforming. Default.
    #[default]
    Conforming,
    /// Points needed only to complete the hierarchy are fictitious: height
    /// interpolated at the midpoint of their diagonal, never transmitted.
    Fictitious {
        /// Also split the unsplit neighbour through each fictitious point (no
        /// T-junction, same surface). `false` is paper 000's faithful variant,
        /// with hanging vertices.
        watertight: bool,
    },
}

impl Mode {
    /// A short name for reports: `conforming`, `fictitious` or
    /// `fictitious-faithful`.
    pub fn name(&self) -> &'static str {
        match self {
            Mode::Conforming => "conforming",
            Mode::Fictitious { watertight: true } => "fictitious",
            Mode::Fictitious { watertight: false } => "fictitious-faithful",
        }
    }

    /// True when the mesh has no T-junction (everything but the faithful variant).
    pub fn is_conforming(&self) -> bool {
        !matches!(self, Mode::Fictitious { watertight: false })
    }

    /// The dependency closure this mode uses.
    pub fn closure(&self) -> Closure {
        match self {
            Mode::Conforming => Closure::Conforming,
            Mode::Fictitious { watertight: true } => Closure::Watertight,
            Mode::Fictitious { watertight: false } => Closure::Faithful,
        }
    }
}

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
    let mut marks = Marks::new(hier, opts.mode.closure());
    marks.seed_border();
    refine_marks_from(grid, criterion, opts, marks)
}

/// [`refine_marks`] continued from `marks`, closed marks of an earlier
/// refinement of the same `grid` in the same mode (e.g. at a larger
/// tolerance): points are only added, so the result's selection contains
/// `marks`' selection, and at the fixed point every leaf meets `criterion`
/// with its actual heights, as in [`refine`]. The progressive marks streams
/// ([`crate::stream_marks`]) build their nested steps this way.
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
    let mut accepted: HashSet<LeafKey, FastHash> = HashSet::default();
    let mut rounds = 0;
    loop {
        rounds += 1;
        let (leaves, z) = walk(grid, &marks);
        let fresh: Vec<(Leaf, LeafKey)> = leaves
            .into_iter()
            .map(|l| (l, key(&l, &z, &hier)))
            .filter(|(_, k)| !accepted.contains(k))
            .collect();
        let verdicts: Vec<Verdict> = fresh
            .par_iter()
            .map(|(l, _)| judge(grid, &marks, &z, l, criterion))
            .collect();
        let mut added = false;
        for ((_, k), v) in fresh.into_iter().zip(verdicts) {
            match v {
                Verdict::Accept => {
                    accepted.insert(k);
                }
                Verdict::Select(points) => {
                    for p in points.into_iter().flatten() {
                        added |= marks.select(p);
                    }
                }
            }
        }
        if !added {
            break;
        }
        marks.close();
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
    let (leaves, z) = walk(grid, marks);
    let (mesh, transmitted, fictitious) = emit(grid, marks, &z, &leaves);
    Refined {
        mesh,
        mode,
        transmitted_points: transmitted,
        fictitious_points: fictitious,
        line_triangles: marks.hanging_vertices(),
        rounds: 0,
    }
}

/// A leaf of the current mesh.
#[derive(Debug, Clone, Copy)]
struct Leaf {
    tri: Tri,
    depth: u32,
}

/// A leaf and its vertex heights: its verdict cannot change while this holds.
type LeafKey = (u64, u64, u64);

/// A multiply–rotate hasher for [`LeafKey`]s (well-mixed integer keys; no
/// denial-of-service concern here).
#[derive(Default, Clone, Copy)]
struct FastHash;

impl std::hash::BuildHasher for FastHash {
    type Hasher = FastHasher;
    fn build_hasher(&self) -> FastHasher {
        FastHasher(0)
    }
}

struct FastHasher(u64);

impl std::hash::Hasher for FastHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

fn key(l: &Leaf, z: &[f32], hier: &Hierarchy) -> LeafKey {
    let k = |p: Pt| ((hier.index(p) as u64) << 32) | z[hier.index(p)].to_bits() as u64;
    (k(l.tri.a), k(l.tri.b), k(l.tri.c))
}

/// Walks the marked tree: the leaves inside the grid, and the mesh height of
/// every sample (only vertices' entries are meaningful).
fn walk(grid: &HeightGrid, marks: &Marks) -> (Vec<Leaf>, Vec<f32>) {
    let mut z = grid.heights().to_vec();
    let mut leaves = Vec::new();
    let hier = *marks.hierarchy();
    let mut stack: Vec<(Tri, bool, u32)> = hier.roots().iter().map(|&r| (r, false, 0)).collect();
    while let Some((t, inside, depth)) = stack.pop() {
        let inside = inside
            || match hier.place(&t) {
                Placement::Outside => continue,
                Placement::Straddling => false,
                Placement::Inside => true,
            };
        if t.is_unit() {
            if inside {
                leaves.push(Leaf { tri: t, depth });
            }
            continue;
        }
        if inside && !marks.splits(&t) {
            leaves.push(Leaf { tri: t, depth });
            continue;
        }
        let m = t.mid();
        if inside && marks.is_fictitious(m) {
            let (za, zb) = (z[hier.index(t.a)] as f64, z[hier.index(t.b)] as f64);
            z[hier.index(m)] = (0.5 * (za + zb)) as f32;
        }
        let (c0, c1) = t.children();
        stack.push((c1, inside, depth + 1));
        stack.push((c0, inside, depth + 1));
    }
    (leaves, z)
}

enum Verdict {
    Accept,
    /// Points to select: the leaf's split point and up to three vertices.
    Select([Option<Pt>; 4]),
}

/// Asks the criterion about one leaf with its actual heights (rule 4).
fn judge(
    grid: &HeightGrid,
    marks: &Marks,
    z: &[f32],
    l: &Leaf,
    criterion: &dyn Criterion,
) -> Verdict {
    let hier = marks.hierarchy();
    let t = l.tri;
    let p = [t.a, t.b, t.c];
    let zs = p.map(|q| z[hier.index(q)] as f64);
    let corners = [0, 1, 2].map(|k| [p[k][0] as f64, p[k][1] as f64, zs[k]]);
    let e = Element {
        corners: &corners,
        depth: l.depth,
        vertical_error_m: max_deviation(grid, p, zs),
        grid,
    };
    if !criterion.wants_split(&e) {
        return Verdict::Accept;
    }
    let mut out = [None; 4];
    if !t.is_unit() {
        out[0] = Some(t.mid());
    }
    let zero = Element {
        vertical_error_m: 0.0,
        ..e
    };
    let zero_wants = criterion.wants_split(&zero);
    for k in 0..3 {
        if !marks.is_fictitious(p[k]) || zero_wants {
            continue;
        }
        let dev = (zs[k] - grid.heights()[hier.index(p[k])] as f64).abs();
        let own = Element {
            vertical_error_m: dev,
            ..e
        };
        if dev > 0.0 && criterion.wants_split(&own) {
            out[k + 1] = Some(p[k]);
        }
    }
    Verdict::Select(out)
}

/// Builds the mesh from the leaves; returns it with the counts of real and
/// fictitious vertices.
fn emit(grid: &HeightGrid, marks: &Marks, z: &[f32], leaves: &[Leaf]) -> (Mesh, usize, usize) {
    let hier = marks.hierarchy();
    let n = grid.len();
    let mut bits = vec![0u64; n.div_ceil(64)];
    let mut tris = Vec::with_capacity(leaves.len());
    for l in leaves {
        let t = l.tri;
        let (a, b, c) = if orient_up(t.a, t.b, t.c) > 0 {
            (t.a, t.b, t.c)
        } else {
            (t.b, t.a, t.c)
        };
        let ids = [
            hier.index(a) as u32,
            hier.index(b) as u32,
            hier.index(c) as u32,
        ];
        for &i in &ids {
            bits[(i / 64) as usize] |= 1u64 << (i % 64);
        }
        tris.push(ids);
    }
    let mut prefix = Vec::with_capacity(bits.len());
    let mut total = 0u32;
    for &word in &bits {
        prefix.push(total);
        total += word.count_ones();
    }
    let w = grid.width() as u32;
    let mut vertices = Vec::with_capacity(total as usize);
    let mut fictitious = 0;
    for (k, &word) in bits.iter().enumerate() {
        let mut rest = word;
        while rest != 0 {
            let bit = rest.trailing_zeros();
            rest &= rest - 1;
            let i = k as u32 * 64 + bit;
            let p = [i % w, i / w];
            if marks.is_fictitious(p) {
                fictitious += 1;
            }
            vertices.push(MeshVertex {
                col: p[0],
                row: p[1],
                z_m: z[i as usize],
            });
        }
    }
    for t in &mut tris {
        for i in t.iter_mut() {
            let (word, bit) = ((*i / 64) as usize, *i % 64);
            let below = bits[word] & ((1u64 << bit) - 1);
            *i = prefix[word] + below.count_ones();
        }
    }
    let transmitted = vertices.len() - fictitious;
    (
        Mesh {
            vertices,
            triangles: tris,
        },
        transmitted,
        fictitious,
    )
}
