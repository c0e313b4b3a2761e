//! The best (mesh, texture) pair under a memory budget: paper
//! `004_ab8d08b3e6a5a70a.txt` §3.
//!
//! * [`lists`]: the mesh list — the bitree and the restricted quadtree at a
//!   series of tolerances through [`crate::Mesher`], each with the paper's
//!   `D(M)` ([`crate::mesh::metrics::distortion_m2`]) and a byte count from a
//!   byte model the caller states;
//! * [`choice`]: the paper's greedy scan, the exact optimum over the two
//!   lists, the weighted distortion `α·D(M) + β·D(T)` and the paper's
//!   optional rule "no more polygons than the texture has elements".
//!
//! The textures come from [`crate::texture`].

pub mod choice;
pub mod lists;

pub use choice::{choose, greedy, optimum, Candidate, Choice, Pair, PairError, PairOptions};
pub use lists::{mesh_list, mesh_list_with_progress, MeshCandidate, MeshListOptions};
