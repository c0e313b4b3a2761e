//! Mesh writers (OBJ, PLY, STL, GLB): being written.
