//! # cota-core
//!
//! The I/O-free heart of cota, a terrain level-of-detail engine implementing the
//! system of the five papers in `../shared/seeds/` (summarised in
//! `../shared/design/PAPERS.md`). Nothing in this crate opens a file; readers
//! and writers live in `cota-io`.
//!
//! The modules are families, in the order of the pipeline:
//! * [`grid`]: the [`HeightGrid`] (voids are NaN) and its georeference, the
//!   local frame in metres, windows, the [`mosaic`] of adjacent tiles and the
//!   void fill ([`fill_voids`]);
//! * [`hierarchy`]: the implicit right-triangle tree over any W×H grid, its
//!   levels and the one clipped top-down walk;
//! * [`bitree`]: the exact error of every split point ([`Bitree`], built once)
//!   and the conforming extraction by error or budget (many times);
//! * [`criteria`]: what drives a refinement ([`Criterion`]);
//! * [`refine`](mod@refine): the criterion-driven refinement in the three
//!   [`Mode`]s, fictitious points included;
//! * [`quadtree`]: the restricted quadtree, paper 000's baseline;
//! * [`mesher`]: one entry point, [`mesh()`] / [`Mesher`], over all of those;
//! * [`mesh`](mod@mesh): the [`Mesh`], the exact [`measure`]s and the one
//!   invariant checker ([`check_mesh`]);
//! * [`strip`]: triangle strips; [`stream`]: the progressive stream;
//!   [`compare`]: paper 000's tables;
//! * [`texture`]: imagery over the DEM and paper 004's texture quadtree;
//!   [`pair`](mod@pair): paper 004's best (mesh, texture) pair under a
//!   memory budget.
//! * [`tin`]: an irregular triangulation (TIN) with the same guaranteed
//!   error and fewer triangles ([`tin::build`]);
//! * [`tiles`]: web-map tile pyramids cut from one hierarchy over the
//!   tiling's lattice, each tile within its zoom's bound;
//! * [`progress`]: the `(done, total)` callbacks the long entry points
//!   (`*_with_progress`) report to.
//!
//! ```
//! use cota_core::{check_mesh, GeoRef, HeightGrid, MaxVerticalError, MeshPlan, Mesher, Mode};
//! let (w, h) = (65, 40);
//! let heights: Vec<f32> = (0..w * h)
//!     .map(|i| 300.0 + 80.0 * ((i % w) as f32 * 0.11).sin() * ((i / w) as f32 * 0.07).cos())
//!     .collect();
//! let grid = HeightGrid::new(w, h, heights, GeoRef::unreferenced(30.0)).unwrap();
//! let mesher = Mesher::new(&grid); // prepared once, meshed many times
//! for e in [1.0, 5.0] {
//!     let bound = MaxVerticalError::new(e).unwrap();
//!     let conforming = mesher.mesh(&MeshPlan::new(&bound)).unwrap();
//!     let fictitious = MeshPlan::new(&bound).with_mode(Mode::Fictitious { watertight: true });
//!     let fictitious = mesher.mesh(&fictitious).unwrap();
//!     for m in [conforming, fictitious] {
//!         let report = check_mesh(&grid, &m.mesh, &m.check).unwrap();
//!         assert!(report.metrics.max_error_m <= e);
//!     }
//! }
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod bitree;
pub mod compare;
pub mod criteria;
pub mod error;
pub mod grid;
pub mod hierarchy;
pub mod mesh;
pub mod mesher;
pub mod pair;
mod par;
pub mod progress;
pub mod quadtree;
pub mod refine;
pub mod relief;
pub mod stream;
pub mod strip;
#[cfg(test)]
#[allow(clippy::unwrap_used, reason = "tests")]
mod testing;
pub mod texture;
pub mod tiles;
pub mod tin;

// The public face: the types and entry points of the pipeline, in its
// order; everything else by its module's path.
pub use bitree::{Bitree, ExtractOptions};
pub use criteria::{Criterion, CriterionKind, CriterionOptions, MaxVerticalError};
pub use error::{MeshError, Result};
pub use grid::mosaic::{mosaic, MosaicOptions, SeamPolicy, SeamReport};
pub use grid::voids::{fill_voids, FillMethod, FillOptions, VoidPolicy};
pub use grid::{Crs, GeoRef, GeoTransform, GridError, HeightGrid, LonLat, PixelIs};
pub use mesh::check::{check_mesh, CheckOptions};
pub use mesh::metrics::{measure, Metrics};
pub use mesh::{Mesh, MeshVertex};
pub use mesher::{mesh, HierarchyKind, MeshPlan, Meshed, Mesher};
pub use quadtree::{QuadOptions, QuadTree};
pub use refine::{refine, Mode, RefineOptions};
pub use strip::{stripify_bitree, Strip, StripMethod};
