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
pub mod criteria;
pub mod error;
pub mod grid;
pub mod hierarchy;
pub mod mesh;
mod par;
pub mod quadtree;
pub mod refine;
pub mod stream;
pub mod strip;

pub use bitree::Bitree;
pub use bitree::PointCounts;
pub use bitree::{ExtractOptions, Extraction, Target};
pub use criteria::{
    AccumulatedCurvature, All, Any, Criterion, CriterionKind, CriterionOptions, Element,
    EuclideanDistance, IlluminationMask, MaxVerticalError, Paper001, Paper003, RelativeSize,
    ScreenSpaceError,
};
pub use error::{MeshError, Result};
pub use grid::mosaic::{mosaic, Mosaic, MosaicError, MosaicOptions, SeamPolicy, SeamReport};
pub use grid::voids::{fill_voids, FillMethod, FillOptions, FillReport, VoidError, VoidPolicy};
pub use grid::{Crs, GeoRef, GridError, HeightGrid, PixelIs};
pub use mesh::check::{check_mesh, CheckError, CheckOptions, CheckReport, Violation};
pub use mesh::metrics::{measure, Metrics};
pub use mesh::{Mesh, MeshVertex};
pub use quadtree::{QuadExtraction, QuadTree};
