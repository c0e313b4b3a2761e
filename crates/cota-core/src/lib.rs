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
pub mod check;
pub mod criteria;
pub mod curvature;
pub mod error_code;
pub mod extract;
pub mod fictitious;
pub mod grid;
pub mod hierarchy;
pub mod light;
pub mod mesh;
pub mod metrics;
pub mod mosaic;
pub mod points;
pub mod quadtree;
pub mod quadtree_templates;
pub mod raster;
pub mod refine;
pub mod stream;
pub mod stream_coder;
pub mod stream_marks;
pub mod strip;
pub mod strip_cells;
pub mod strip_quadtree;
pub mod tiles;
pub mod view;
pub mod voids;

pub use bitree::{Bitree, MeshError};
pub use check::{check_mesh, CheckError, CheckOptions, CheckReport, Violation};
pub use criteria::{
    All, Any, Criterion, Element, EuclideanDistance, MaxVerticalError, RelativeSize,
};
pub use extract::{ExtractOptions, Extraction, Target};
pub use grid::{Crs, GeoRef, GridError, HeightGrid, PixelIs};
pub use mesh::{Mesh, MeshVertex};
pub use metrics::{measure, Metrics};
pub use mosaic::{mosaic, Mosaic, MosaicError, MosaicOptions, SeamPolicy, SeamReport};
pub use points::PointCounts;
pub use quadtree::{QuadExtraction, QuadTree};
pub use voids::{fill_voids, FillMethod, FillOptions, FillReport, VoidError, VoidPolicy};

/// Runs `f` on a rayon worker thread. A parallel section entered from outside
/// the pool hands its work to the pool and waits to be woken (about 30 µs per
/// section on the 2-core benchmark machine); one entered from a worker costs
/// well under a microsecond. So each public entry point that runs several
/// parallel sections enters the pool once, here.
pub(crate) fn on_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    if rayon::current_thread_index().is_some() {
        f()
    } else {
        rayon::scope(|_| f())
    }
}
