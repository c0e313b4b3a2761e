//! `cota mesh --voids hole`: the checks of the flags it works with, and the
//! cut of the mesh (`cota_core::mesh::holes`).

use cota_core::mesh::holes::{cut_holes, HoleReport, VoidMask};
use cota_core::refine::Mode;
use cota_core::{HeightGrid, Meshed};

use crate::args::{HierarchyArg, MeshArgs, MeshKindArg, Voids};

/// The voids of the input, kept while the grid is filled for meshing.
pub struct Holes {
    /// Where the voids are.
    pub mask: VoidMask,
    /// The grid as read, voids NaN: the checker and the metrics use it.
    pub grid: HeightGrid,
}

impl Holes {
    /// With `--voids hole`, the voids of `grid` (before it is filled).
    pub fn of(a: &MeshArgs, grid: &HeightGrid) -> Option<Holes> {
        matches!(a.voids, Voids::Hole).then(|| Holes {
            mask: VoidMask::new(grid),
            grid: grid.clone(),
        })
    }
}

/// Refuses the flags `--voids hole` does not work with, clearly.
pub fn validate(a: &MeshArgs) -> anyhow::Result<()> {
    if !matches!(a.voids, Voids::Hole) {
        return Ok(());
    }
    let refuse = |what: &str| anyhow::bail!("--voids hole: {what}");
    if a.base_m.is_some() || a.base_mm.is_some() {
        return refuse(
            "expected no --base-m (a solid with holes in its top is not closed; fill the voids to print it)",
        );
    }
    if a.hierarchy != HierarchyArg::Bitree || a.mesh != MeshKindArg::Bitree {
        return refuse("expected the default --hierarchy bitree and --mesh bitree");
    }
    if a.refine.mode.mode() != Mode::Conforming {
        return refuse("expected --mode conforming");
    }
    if a.max_triangles.is_some() {
        return refuse("expected --max-error or a criterion, not --max-triangles");
    }
    if a.strip || a.strip_method.is_some() {
        return refuse("expected no --strip (strips cover the whole rectangle)");
    }
    Ok(())
}

/// Drops the triangles touching a void from `m`; its check then requires
/// the coverage of the valid region only.
pub fn cut(m: &mut Meshed, holes: &Holes) -> HoleReport {
    let (mesh, report) = cut_holes(&m.mesh, &holes.mask);
    m.mesh = mesh;
    m.check = m.check.with_holes(true);
    report
}

/// The `--voids` policy as the report names it.
pub fn policy_name(v: Voids) -> &'static str {
    match v {
        Voids::Fill => "fill",
        Voids::Idw => "idw",
        Voids::Refuse => "refuse",
        Voids::Hole => "hole",
    }
}
