//! # cota-core
//!
//! The I/O-free heart of cota, a terrain level-of-detail engine implementing the
//! system of the five papers in `../shared/seeds/` (summarised in
//! `../shared/design/PAPERS.md`).
//!
//! * [`HeightGrid`]: a W×H grid of heights in metres with per-sample validity
//!   (voids are NaN) and its georeference ([`GeoRef`]).
//! * [`Mesh`]: an indexed triangle mesh whose vertices sit on grid samples.
//!
//! Nothing in this crate opens a file; readers and writers live in `cota-io`.
#![warn(missing_docs)]

pub mod bitree;
pub mod compare;
pub mod criteria;
pub mod error;
pub mod grid;
pub mod hierarchy;
pub mod mesh;
pub mod mesher;
mod par;
pub mod quadtree;
pub mod refine;
pub mod stream;
pub mod strip;
#[cfg(test)]
#[allow(clippy::unwrap_used, reason = "tests")]
mod testing;

// The public face: the types and entry points of the pipeline, in its
// order; everything else by its module's path.
pub use bitree::{Bitree, ExtractOptions};
pub use criteria::{Criterion, CriterionKind, CriterionOptions, MaxVerticalError};
pub use error::{MeshError, Result};
pub use grid::mosaic::{mosaic, MosaicOptions, SeamPolicy, SeamReport};
pub use grid::voids::{fill_voids, FillMethod, FillOptions, VoidPolicy};
pub use grid::{Crs, GeoRef, GridError, HeightGrid, PixelIs};
pub use mesh::check::{check_mesh, CheckOptions};
pub use mesh::metrics::{measure, Metrics};
pub use mesh::{Mesh, MeshVertex};
pub use mesher::{mesh, HierarchyKind, MeshPlan, Meshed, Mesher};
pub use quadtree::{QuadOptions, QuadTree};
pub use refine::{refine, Mode, RefineOptions};
pub use strip::{stripify_bitree, Strip, StripMethod};
