//! One entry point to "mesh this grid": hierarchy × mode × criterion ×
//! target, prepared once and meshed many times.
//!
//! Papers `000_ebf7e3a88dffd361.txt` (the bitree, its modes and paper 000's
//! comparison with the restricted quadtree) and `001_49f2c365e8c41172.txt`
//! (refinement by a criterion). A [`MeshPlan`] names what to build; a
//! [`Mesher`] holds what the plans of one grid share, each built the first
//! time a plan needs it and kept:
//! * the bitree's error map ([`Bitree`]), for the plans it answers alone:
//!   the bitree in conforming mode with a criterion that is a pure vertical
//!   bound ([`Criterion::vertical_bound_m`]), by error or by triangle budget.
//!   Each such mesh is then an extraction, in time proportional to its size;
//! * the restricted quadtree's side errors ([`QuadTree`]);
//! * the grid's curvature map, which the curvature criteria borrow
//!   ([`Mesher::criterion`]).
//!
//! Every other plan (the fictitious modes, any other criterion) runs the
//! criterion-driven refinement of [`crate::refine`](mod@crate::refine), which judges every leaf
//! with its actual heights. Whatever the path, the result ([`Meshed`]) says
//! what the mesh promises ([`Meshed::bound_m`], [`Meshed::check`]) and
//! counts its points as paper 000 does.

use std::sync::OnceLock;

use crate::bitree::{Bitree, ExtractOptions, Extraction, PointCounts, Progress};
use crate::criteria::{
    Criterion, CriterionError, CriterionKind, CriterionOptions, CurvatureMap, MaxVerticalError,
};
use crate::error::{MeshError, Result};
use crate::grid::extend::{extend_clamped, extended_size};
use crate::grid::HeightGrid;
use crate::mesh::check::CheckOptions;
use crate::mesh::clip::clip_to;
use crate::mesh::Mesh;
use crate::quadtree::{QuadOptions, QuadTree};
use crate::refine::{refine, Mode, RefineOptions};
use crate::tin::TinOptions;

/// Which hierarchy meshes the grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum HierarchyKind {
    /// The right-triangle bitree (paper 000). Default.
    #[default]
    Bitree,
    /// The restricted quadtree (Pajarola 1998), the baseline of paper 000's
    /// comparison: conforming mode, no triangle budget.
    Quadtree(QuadOptions),
    /// An irregular triangulation ([`crate::tin`]) decimated from the
    /// bitree's mesh: the same guaranteed vertical bound with fewer
    /// triangles. Conforming mode with a vertical bound (or a budget) only;
    /// `lock_border` as [`TinOptions::lock_border`].
    Tin {
        /// See [`TinOptions::lock_border`].
        lock_border: bool,
    },
}

impl HierarchyKind {
    /// `bitree` or `quadtree`, for reports.
    pub fn name(&self) -> &'static str {
        match self {
            HierarchyKind::Bitree => "bitree",
            HierarchyKind::Quadtree(_) => "quadtree",
            HierarchyKind::Tin { .. } => "tin",
        }
    }
}

/// What to mesh: a hierarchy, a mode, a criterion and, instead of the
/// criterion's bound, a triangle budget.
#[derive(Clone, Copy)]
#[non_exhaustive]
pub struct MeshPlan<'c> {
    /// The hierarchy. Default: [`HierarchyKind::Bitree`].
    pub hierarchy: HierarchyKind,
    /// How points needed only by the hierarchy are treated. Default:
    /// [`Mode::Conforming`].
    pub mode: Mode,
    /// What drives refinement.
    pub criterion: &'c dyn Criterion,
    /// At most this many triangles, with the smallest error that allows
    /// (the bitree in conforming mode with a pure vertical bound only, whose
    /// value it replaces). Default: `None`.
    pub max_triangles: Option<usize>,
    /// Mesh a grid with an odd span (web tiles: 256 or 512 wide) on its
    /// clamp-extended grid and clip the mesh back to the real rectangle
    /// ([`crate::grid::extend`], [`crate::mesh::clip`]), so that its border
    /// is as coarse as a `2^k + 1` grid's. Only the error map's extraction
    /// by error follows (the bitree in conforming mode with a vertical bound
    /// and no budget); every other plan meshes the grid as it is, and so
    /// does every grid whose spans are even. Set it to false for a mesh made
    /// of the grid's own hierarchy triangles (strips, paper 000's
    /// accounting). Default: true.
    pub extend_odd_spans: bool,
}

impl<'c> MeshPlan<'c> {
    /// The bitree in conforming mode, refined by `criterion`.
    pub fn new(criterion: &'c dyn Criterion) -> Self {
        MeshPlan {
            hierarchy: HierarchyKind::Bitree,
            mode: Mode::Conforming,
            criterion,
            max_triangles: None,
            extend_odd_spans: true,
        }
    }

    /// Sets [`MeshPlan::hierarchy`].
    pub fn with_hierarchy(mut self, hierarchy: HierarchyKind) -> Self {
        self.hierarchy = hierarchy;
        self
    }

    /// Sets [`MeshPlan::mode`].
    pub fn with_mode(mut self, mode: Mode) -> Self {
        self.mode = mode;
        self
    }

    /// Sets [`MeshPlan::extend_odd_spans`].
    pub fn with_extend_odd_spans(mut self, yes: bool) -> Self {
        self.extend_odd_spans = yes;
        self
    }

    /// Sets [`MeshPlan::max_triangles`].
    pub fn with_max_triangles(mut self, n: Option<usize>) -> Self {
        self.max_triangles = n;
        self
    }

    /// The vertical bound the bitree's error map answers this plan with:
    /// `Some` for the bitree in conforming mode with a pure vertical bound
    /// ([`Criterion::vertical_bound_m`]), the fast path of the module docs.
    pub fn error_map_bound_m(&self) -> Option<f64> {
        match (self.hierarchy, self.mode) {
            (HierarchyKind::Bitree | HierarchyKind::Tin { .. }, Mode::Conforming) => {
                self.criterion.vertical_bound_m()
            }
            _ => None,
        }
    }

    /// Whether this plan meshes `grid` on its clamp-extended grid
    /// ([`MeshPlan::extend_odd_spans`]): the size to extend to, if so.
    pub fn extension_for(&self, grid: &HeightGrid) -> Option<(usize, usize)> {
        let follows = self.extend_odd_spans
            && self.hierarchy == HierarchyKind::Bitree
            && self.max_triangles.is_none()
            && self.error_map_bound_m().is_some();
        follows
            .then(|| extended_size(grid.width(), grid.height()))
            .flatten()
    }

    /// Refuses the combinations no hierarchy offers.
    fn validate(&self) -> Result<()> {
        let quadtree = matches!(self.hierarchy, HierarchyKind::Quadtree(_));
        if quadtree && self.mode != Mode::Conforming {
            return Err(MeshError::UnsupportedPlan(
                "the restricted quadtree meshes in conforming mode only",
            ));
        }
        let tin = matches!(self.hierarchy, HierarchyKind::Tin { .. });
        if tin && self.error_map_bound_m().is_none() {
            return Err(MeshError::UnsupportedPlan(
                "a TIN needs conforming mode and a vertical bound (or a triangle budget)",
            ));
        }
        if self.max_triangles.is_some() && self.error_map_bound_m().is_none() {
            return Err(MeshError::UnsupportedPlan(
                "a triangle budget needs the bitree in conforming mode with a vertical bound",
            ));
        }
        Ok(())
    }
}

/// A mesh and what it promises.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct Meshed {
    /// The mesh (vertices on samples, triangles counter-clockwise from above;
    /// fictitious vertices at their interpolated height).
    pub mesh: Mesh,
    /// The vertical bound that holds at every sample, metres: the criterion's
    /// (or, by budget, the threshold found); `None` when the criterion
    /// promises none.
    pub bound_m: Option<f64>,
    /// The criterion's name for reports (by budget: the bound found).
    pub criterion: String,
    /// Vertices with their sample's real height: the points a progressive
    /// transmission sends (paper 000).
    pub transmitted_points: usize,
    /// Vertices with an interpolated height (fictitious modes).
    pub fictitious_points: usize,
    /// Hanging vertices of the faithful mode, each closed by one "line
    /// triangle" in paper 000's strips.
    pub line_triangles: usize,
    /// Rounds of the criterion-driven refinement (1 for the quadtree; `None`
    /// for an extraction from the error map).
    pub rounds: Option<usize>,
    /// What [`crate::check_mesh`] must verify of the mesh.
    pub check: CheckOptions,
    /// The restricted quadtree's count of base, selected and added points by
    /// splits, valid for any criterion ([`crate::quadtree::QuadExtraction`]);
    /// `None` for the bitree.
    pub split_points: Option<PointCounts>,
    /// The size of the clamp-extended grid the mesh was made on and clipped
    /// from ([`MeshPlan::extend_odd_spans`]); `None` when it is the grid's
    /// own hierarchy.
    pub extended_to: Option<[usize; 2]>,
}

/// What the plans of one grid share, each part built the first time a plan
/// needs it (see the module docs).
///
/// ```
/// use cota_core::{check_mesh, GeoRef, HeightGrid, MaxVerticalError, MeshPlan, Mesher, Mode};
/// let (w, h) = (33, 21);
/// let heights: Vec<f32> = (0..w * h)
///     .map(|i| ((i % w) as f32 * 0.4).sin() * 20.0 + ((i / w) as f32 * 0.3).cos() * 15.0)
///     .collect();
/// let grid = HeightGrid::new(w, h, heights, GeoRef::unreferenced(30.0)).unwrap();
/// let mesher = Mesher::new(&grid);
/// for e in [0.5, 2.0] {
///     let c = MaxVerticalError::new(e).unwrap();
///     for mode in Mode::ALL {
///         let m = mesher.mesh(&MeshPlan::new(&c).with_mode(mode)).unwrap();
///         assert_eq!(m.bound_m, Some(e));
///         check_mesh(&grid, &m.mesh, &m.check).unwrap();
///     }
/// }
/// ```
#[derive(Debug)]
pub struct Mesher<'g> {
    grid: &'g HeightGrid,
    bitree: OnceLock<Bitree<'g>>,
    /// The bitree of the clamp-extended grid ([`MeshPlan::extend_odd_spans`]).
    extended: OnceLock<Bitree<'static>>,
    quadtree: OnceLock<QuadTree<'g>>,
    curvature: OnceLock<CurvatureMap>,
}

impl<'g> Mesher<'g> {
    /// A mesher for `grid`; nothing is built yet.
    pub fn new(grid: &'g HeightGrid) -> Self {
        Mesher {
            grid,
            bitree: OnceLock::new(),
            extended: OnceLock::new(),
            quadtree: OnceLock::new(),
            curvature: OnceLock::new(),
        }
    }

    /// The grid.
    pub fn grid(&self) -> &'g HeightGrid {
        self.grid
    }

    /// Builds now what `plan` will need (the error map, reporting
    /// `progress(levels_done, levels_total)`, or the quadtree, reporting
    /// its levels by their work), so that
    /// [`Mesher::mesh`] only refines or extracts.
    ///
    /// # Errors
    /// As [`Bitree::build`] and [`QuadTree::build`].
    pub fn prepare(&self, plan: &MeshPlan<'_>, progress: Progress<'_>) -> Result<()> {
        match plan.hierarchy {
            HierarchyKind::Quadtree(_) => self.quadtree_with(progress).map(|_| ()),
            HierarchyKind::Bitree if plan.extension_for(self.grid).is_some() => {
                self.extended_with(plan, progress).map(|_| ())
            }
            HierarchyKind::Bitree | HierarchyKind::Tin { .. }
                if plan.error_map_bound_m().is_some() =>
            {
                self.bitree_with(progress).map(|_| ())
            }
            HierarchyKind::Bitree | HierarchyKind::Tin { .. } => Ok(()),
        }
    }

    /// The bitree's error map, built on first use.
    ///
    /// # Errors
    /// As [`Bitree::build`].
    pub fn bitree(&self) -> Result<&Bitree<'g>> {
        self.bitree_with(&|_, _| {})
    }

    fn bitree_with(&self, progress: Progress<'_>) -> Result<&Bitree<'g>> {
        if let Some(t) = self.bitree.get() {
            return Ok(t);
        }
        let t = Bitree::build_with_progress(self.grid, progress)?;
        Ok(self.bitree.get_or_init(|| t))
    }

    /// The bitree of the clamp-extended grid, built on first use (`None`
    /// when `plan` does not extend this grid).
    fn extended_with(
        &self,
        plan: &MeshPlan<'_>,
        progress: Progress<'_>,
    ) -> Result<Option<&Bitree<'static>>> {
        let Some((w, h)) = plan.extension_for(self.grid) else {
            return Ok(None);
        };
        if let Some(t) = self.extended.get() {
            return Ok(Some(t));
        }
        // An extension too large for a grid: the grid's own hierarchy.
        let Ok(extended) = extend_clamped(self.grid, w, h) else {
            return Ok(None);
        };
        let t = Bitree::build_owned(extended, progress)?;
        Ok(Some(self.extended.get_or_init(|| t)))
    }

    /// The restricted quadtree, built on first use.
    ///
    /// # Errors
    /// As [`QuadTree::build`].
    pub fn quadtree(&self) -> Result<&QuadTree<'g>> {
        self.quadtree_with(crate::progress::NONE)
    }

    fn quadtree_with(&self, progress: Progress<'_>) -> Result<&QuadTree<'g>> {
        if let Some(t) = self.quadtree.get() {
            return Ok(t);
        }
        let t = QuadTree::build_with_progress(self.grid, progress)?;
        Ok(self.quadtree.get_or_init(|| t))
    }

    /// The grid's curvature map, computed on first use.
    pub fn curvature_map(&self) -> &CurvatureMap {
        self.curvature.get_or_init(|| CurvatureMap::new(self.grid))
    }

    /// The criterion `kind` with `opts` for this grid
    /// ([`CriterionOptions::build`]), borrowing the shared curvature map.
    ///
    /// # Errors
    /// As [`CriterionOptions::build`].
    pub fn criterion(
        &self,
        kind: CriterionKind,
        opts: &CriterionOptions,
    ) -> std::result::Result<Box<dyn Criterion + '_>, CriterionError> {
        opts.build(kind, self.grid, || self.curvature_map())
    }

    /// Meshes the grid as `plan` says (see the module docs).
    ///
    /// # Errors
    /// [`MeshError::UnsupportedPlan`] for a quadtree plan in a fictitious
    /// mode or a budget the error map cannot answer; as [`Bitree::extract`]
    /// (a bad bound, a budget too small), and as the builds for grids that
    /// cannot be meshed.
    pub fn mesh(&self, plan: &MeshPlan<'_>) -> Result<Meshed> {
        plan.validate()?;
        crate::par::on_pool(|| match (plan.hierarchy, plan.error_map_bound_m()) {
            (HierarchyKind::Quadtree(opts), _) => self.quadtree_mesh(plan, &opts),
            (HierarchyKind::Bitree, Some(bound_m)) => self.extract(plan, bound_m),
            (HierarchyKind::Tin { lock_border }, Some(bound_m)) => {
                self.tin(plan, bound_m, lock_border)
            }
            (HierarchyKind::Bitree | HierarchyKind::Tin { .. }, None) => self.refine(plan),
        })
    }

    /// The bitree's conforming mesh from the error map, by bound or budget.
    fn extract(&self, plan: &MeshPlan<'_>, bound_m: f64) -> Result<Meshed> {
        let opts = match plan.max_triangles {
            Some(n) => ExtractOptions::max_triangles(n),
            None => ExtractOptions::max_error_m(bound_m),
        };
        let (x, extended_to) = match self.extended_with(plan, &|_, _| {})? {
            Some(t) => {
                let x = t.extract(&opts)?;
                let (g, e) = (self.grid, t.grid());
                let mesh = clip_to(x.mesh, g.width() as u32, g.height() as u32);
                (Extraction { mesh, ..x }, Some([e.width(), e.height()]))
            }
            None => (self.bitree()?.extract(&opts)?, None),
        };
        let vertices = x.mesh.vertex_count();
        Ok(Meshed {
            mesh: x.mesh,
            bound_m: Some(x.threshold_m),
            criterion: MaxVerticalError {
                max_error_m: x.threshold_m,
            }
            .name(),
            transmitted_points: vertices,
            fictitious_points: 0,
            line_triangles: 0,
            rounds: None,
            check: Mode::Conforming
                .check_options(Some(x.threshold_m))
                .with_clipped_border(extended_to.is_some()),
            split_points: None,
            extended_to,
        })
    }

    /// The criterion-driven refinement of the bitree in the plan's mode.
    fn tin(&self, plan: &MeshPlan<'_>, bound_m: f64, lock_border: bool) -> Result<Meshed> {
        let opts = match plan.max_triangles {
            Some(n) => TinOptions::max_triangles(n),
            None => TinOptions::max_error_m(bound_m),
        }
        .with_lock_border(lock_border);
        let x = crate::tin::build_from(self.bitree()?, &opts)?;
        let vertices = x.mesh.vertex_count();
        Ok(Meshed {
            mesh: x.mesh,
            bound_m: Some(x.threshold_m),
            criterion: MaxVerticalError {
                max_error_m: x.threshold_m,
            }
            .name(),
            transmitted_points: vertices,
            fictitious_points: 0,
            line_triangles: 0,
            rounds: None,
            check: CheckOptions::tin(x.threshold_m),
            split_points: None,
            extended_to: None,
        })
    }

    fn refine(&self, plan: &MeshPlan<'_>) -> Result<Meshed> {
        let r = refine(
            self.grid,
            plan.criterion,
            &RefineOptions::DEFAULT.with_mode(plan.mode),
        )?;
        let bound_m = plan.criterion.vertical_bound_m();
        Ok(Meshed {
            mesh: r.mesh,
            bound_m,
            criterion: plan.criterion.name(),
            transmitted_points: r.transmitted_points,
            fictitious_points: r.fictitious_points,
            line_triangles: r.line_triangles,
            rounds: Some(r.rounds),
            check: plan.mode.check_options(bound_m),
            split_points: None,
            extended_to: None,
        })
    }

    /// The restricted quadtree refined by the plan's criterion.
    fn quadtree_mesh(&self, plan: &MeshPlan<'_>, opts: &QuadOptions) -> Result<Meshed> {
        let x = self.quadtree()?.refine_with(plan.criterion, opts);
        let bound_m = plan.criterion.vertical_bound_m();
        let vertices = x.mesh.vertex_count();
        Ok(Meshed {
            mesh: x.mesh,
            bound_m,
            criterion: plan.criterion.name(),
            transmitted_points: vertices,
            fictitious_points: 0,
            line_triangles: 0,
            rounds: Some(1),
            check: Mode::Conforming.check_options(bound_m),
            split_points: Some(x.points),
            extended_to: None,
        })
    }
}

/// Meshes `grid` as `plan` says: [`Mesher::mesh`] on a mesher used once.
///
/// # Errors
/// As [`Mesher::mesh`].
pub fn mesh(grid: &HeightGrid, plan: &MeshPlan<'_>) -> Result<Meshed> {
    Mesher::new(grid).mesh(plan)
}
