//! meshoptimizer's buffer codecs, as the glTF extension
//! `EXT_meshopt_compression` specifies them (Khronos glTF repository,
//! `extensions/2.0/Vendor/EXT_meshopt_compression/README.md`, Appendix A):
//! pure-Rust encoders written from that bitstream description, and an
//! independent decoder for checks.
//!
//! * [`vertex`]: mode `ATTRIBUTES` (version 0, header `0xa0`), byte-wise
//!   zigzag deltas in blocks of up to 256 elements and groups of 16;
//! * [`index`]: mode `TRIANGLES` (header `0xe1`, edge and vertex FIFOs) and
//!   mode `INDICES` (header `0xd1`, two-baseline varint deltas);
//! * [`decode`]: the three decoders, sharing no code with the encoders, for
//!   the pyramid's check and the tests.
//!
//! The encoders are exact: the decoded buffer is the input, byte for byte
//! (triangles in the given order and rotation; [`encode_triangles_rotated`]
//! may turn each triangle, keeping its winding, and returns what it encoded). They never panic: a layout
//! the format cannot hold is a [`MeshoptError`].

pub mod decode;
pub mod index;
pub mod vertex;

pub use decode::{decode_index_sequence, decode_triangles, decode_vertex_buffer};
pub use index::{encode_index_sequence, encode_triangles, encode_triangles_rotated};
pub use vertex::encode_vertex_buffer;

/// Why a buffer cannot be encoded or decoded.
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
#[error("meshopt: {0}")]
pub struct MeshoptError(pub String);
