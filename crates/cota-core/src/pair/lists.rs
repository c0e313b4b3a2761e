//! The mesh list of paper `004_ab8d08b3e6a5a70a.txt` §3: approximations of
//! one DEM at a series of tolerances, each with its distortion and memory.
//!
//! The paper's list comes from the restricted quadtree; cota adds the
//! bitree. Both are meshed through [`Mesher`] with the exact vertical bound
//! ([`MaxVerticalError`]) at each tolerance (the paper drives its quadtree
//! by accumulated curvature; a vertical bound gives both hierarchies the
//! same, checkable meaning). Each mesh carries:
//! * `D(M)`, m²: [`distortion_m2`], the paper's sum over the centroids of
//!   the full-resolution grid's triangles of `(z − z_approx)²`;
//! * `C(M)`, bytes: whatever byte model the caller passes (`cota pair` uses
//!   the bytes the mesh takes in its textured GLB).
//!
//! Meshes equal to one already in the list (same hierarchy, same triangle
//! count and distortion: the same tolerance band) are left out.

use super::choice::Candidate;
use crate::criteria::MaxVerticalError;
use crate::error::{MeshError, Result};
use crate::mesh::metrics::distortion_m2;
use crate::mesh::Mesh;
use crate::mesher::{HierarchyKind, MeshPlan, Mesher};
use crate::progress::Progress;

/// One mesh of the list.
#[derive(Debug, Clone)]
pub struct MeshCandidate {
    /// The hierarchy that made it.
    pub hierarchy: HierarchyKind,
    /// The vertical bound it was meshed with, metres.
    pub tolerance_m: f64,
    /// The mesh.
    pub mesh: Mesh,
    /// `D(M)`, m².
    pub distortion_m2: f64,
    /// `C(M)`, bytes, in the caller's byte model.
    pub bytes: u64,
    /// What [`crate::check_mesh`] must prove of this mesh (the plan's
    /// bound, conformity, fictitious points), as [`Mesher::mesh`] says.
    pub check: crate::CheckOptions,
}

impl MeshCandidate {
    /// The mesh as a [`Candidate`] of the choice (elements: triangles).
    pub fn candidate(&self) -> Candidate {
        Candidate {
            bytes: self.bytes,
            distortion: self.distortion_m2,
            elements: self.mesh.triangle_count() as u64,
        }
    }
}

/// Options of [`mesh_list`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct MeshListOptions {
    /// The hierarchies, each meshed at every tolerance. Default: the bitree
    /// and the restricted quadtree (its default leaves).
    pub hierarchies: Vec<HierarchyKind>,
    /// The vertical bounds, metres. Default: [`MeshListOptions::series_m`]
    /// of the grid's height range with 10 halvings.
    pub tolerances_m: Vec<f64>,
}

impl MeshListOptions {
    /// Both hierarchies at `tolerances_m`.
    pub fn new(tolerances_m: Vec<f64>) -> Self {
        MeshListOptions {
            hierarchies: vec![
                HierarchyKind::Bitree,
                HierarchyKind::Quadtree(crate::quadtree::QuadOptions::DEFAULT),
            ],
            tolerances_m,
        }
    }

    /// `0` and `range_m / 2^k` for `k = 1..=halvings`, decreasing: a
    /// geometric series from half the height range down to the exact mesh.
    pub fn series_m(range_m: f64, halvings: u32) -> Vec<f64> {
        let mut v: Vec<f64> = (1..=halvings)
            .map(|k| range_m / f64::from(1u32 << k.min(31)))
            .filter(|t| t.is_finite() && *t > 0.0)
            .collect();
        v.push(0.0);
        v
    }

    /// The defaults for `mesher`'s grid (see the fields).
    pub fn for_grid(mesher: &Mesher<'_>) -> Self {
        let range = mesher
            .grid()
            .valid_range()
            .map_or(0.0, |(lo, hi)| f64::from(hi - lo));
        Self::new(Self::series_m(range, 10))
    }
}

/// Meshes `mesher`'s grid with every hierarchy at every tolerance of `opts`,
/// measuring each (module docs); `bytes` is the byte model of `C(M)`.
///
/// # Errors
/// As [`Mesher::mesh`]; [`MeshError::BadMaxError`] for a negative or NaN
/// tolerance.
pub fn mesh_list(
    mesher: &Mesher<'_>,
    opts: &MeshListOptions,
    bytes: &dyn Fn(&Mesh) -> u64,
) -> Result<Vec<MeshCandidate>> {
    mesh_list_with_progress(mesher, opts, bytes, crate::progress::NONE)
}

/// [`mesh_list`], telling `progress(meshes_done, meshes)` after each
/// hierarchy and tolerance (the first mesh of each hierarchy includes its
/// build).
///
/// # Errors
/// As [`mesh_list`].
pub fn mesh_list_with_progress(
    mesher: &Mesher<'_>,
    opts: &MeshListOptions,
    bytes: &dyn Fn(&Mesh) -> u64,
    progress: Progress<'_>,
) -> Result<Vec<MeshCandidate>> {
    let mut out: Vec<MeshCandidate> = Vec::new();
    let total = opts.hierarchies.len() * opts.tolerances_m.len();
    progress(0, total);
    for (h, &hierarchy) in opts.hierarchies.iter().enumerate() {
        for (t, &tol) in opts.tolerances_m.iter().enumerate() {
            progress(h * opts.tolerances_m.len() + t, total);
            let bound = MaxVerticalError::new(tol).map_err(|_| MeshError::BadMaxError(tol))?;
            let plan = MeshPlan::new(&bound).with_hierarchy(hierarchy);
            let meshed = mesher.mesh(&plan)?;
            let (mesh, check) = (meshed.mesh, meshed.check);
            let d = distortion_m2(mesher.grid(), &mesh);
            let seen = out.iter().any(|c| {
                c.hierarchy == hierarchy
                    && c.mesh.triangle_count() == mesh.triangle_count()
                    && c.distortion_m2 == d
            });
            if !seen {
                out.push(MeshCandidate {
                    hierarchy,
                    tolerance_m: tol,
                    bytes: bytes(&mesh),
                    distortion_m2: d,
                    mesh,
                    check,
                });
            }
        }
    }
    progress(total, total);
    Ok(out)
}
