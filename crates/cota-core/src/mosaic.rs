//! Mosaics of adjacent tiles: being written.
