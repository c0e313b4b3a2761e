//! `tileset.json` and the binary subtree files of a 3D Tiles 1.1 terrain
//! pyramid, as CesiumJS's `Cesium3DTilesTerrainProvider` reads them.
//!
//! Written from the 3D Tiles 1.1 specification (implicit tiling: subtree
//! binary format, availability bitstreams in Morton order, tile metadata in
//! a property table; metadata semantics `TILE_MINIMUM_HEIGHT`,
//! `TILE_MAXIMUM_HEIGHT`, `TILE_BOUNDING_SPHERE`,
//! `TILE_HORIZON_OCCLUSION_POINT`) and CesiumJS 1.145's
//! `Cesium3DTilesTerrainProvider.js` (notes in `docs/3dtiles-terrain.md`):
//!
//! * the explicit root has exactly two children, the west (longitude < 0)
//!   and east roots of the geographic two-root quadtree, each an implicit
//!   quadtree whose level `z` is the tile's zoom, `x` its column within the
//!   hemisphere and `y` its row from the south (quantized-mesh's TMS rows);
//! * `OUT/{root}/{level}/{x}/{y}.glb` the tiles, and
//!   `OUT/{root}/subtrees/{level}/{x}/{y}.subtree` the subtrees
//!   ([`subtree_levels`] levels each: the pyramid's levels split evenly,
//!   at most [`MAX_SUBTREE_LEVELS`] a subtree);
//! * a tile is available exactly when it was written: the pyramid's tiles
//!   (both level-0 tiles always; below them the tiles that meet the data)
//!   and the fill tiles that give every tile with a child all four
//!   ([`cota_core::tiles::Prepared::is_fill`]): the specification's REPLACE
//!   refinement draws a refined tile only through its children, so a
//!   missing quadrant is a hole in a generic client (CesiumJS's provider
//!   would upsample the parent there, as for quantized-mesh); fill tiles
//!   have no children;
//! * a tile's `geometricError` is its zoom's bound `e_z` (the root's halves
//!   at each level, as `e_z` does).

use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, PI};

use cota_core::tiles::TileId;
use serde_json::{json, Value};

use super::glb_tile::TileMeta;

/// The most levels a subtree file holds (its child bitstream is
/// `4^levels` bits: 8 KiB at 8).
pub const MAX_SUBTREE_LEVELS: u8 = 8;

/// Levels per subtree for a pyramid of zooms `0..=max_zoom`: the fewest
/// layers of subtrees of at most [`MAX_SUBTREE_LEVELS`] levels, evenly
/// split (zooms 0–12: two layers of 7, so no subtree holds a lone level).
pub fn subtree_levels(max_zoom: u8) -> u8 {
    let levels = u32::from(max_zoom) + 1;
    let layers = levels.div_ceil(u32::from(MAX_SUBTREE_LEVELS));
    levels.div_ceil(layers) as u8
}

/// The path of a tile's GLB relative to the output: `{root}/{z}/{x}/{y}.glb`.
pub fn glb_rel_path(t: TileId) -> String {
    let (root, x) = implicit_x(t);
    format!("{root}/{}/{x}/{}.glb", t.z, t.y)
}

/// The root (0 west, 1 east) and column within it.
fn implicit_x(t: TileId) -> (u32, u32) {
    let per_root = 1u32 << t.z;
    (t.x / per_root, t.x % per_root)
}

/// The schema of the tile metadata (found by semantic; names are free).
fn schema() -> Value {
    let scalar = |semantic: &str| json!({"type": "SCALAR", "componentType": "FLOAT64", "semantic": semantic});
    json!({
        "id": "cota_terrain",
        "classes": {"tile": {"properties": {
            "minimumHeight": scalar("TILE_MINIMUM_HEIGHT"),
            "maximumHeight": scalar("TILE_MAXIMUM_HEIGHT"),
            "boundingSphere": {"type": "SCALAR", "componentType": "FLOAT64", "array": true,
                "count": 4, "semantic": "TILE_BOUNDING_SPHERE"},
            "horizonOcclusionPoint": {"type": "VEC3", "componentType": "FLOAT64",
                "semantic": "TILE_HORIZON_OCCLUSION_POINT"},
        }}}
    })
}

/// `tileset.json` for tiles up to `max_zoom`, the zoom-0 bound `e0_m` and
/// heights within `[min_m, max_m]`.
pub fn tileset_json(max_zoom: u8, e0_m: f64, min_m: f64, max_m: f64) -> Value {
    let levels = subtree_levels(max_zoom);
    let child = |root: u32| {
        let west = if root == 0 { -PI } else { 0.0 };
        json!({
            "boundingVolume": {"region": [west, -FRAC_PI_2, west + PI, FRAC_PI_2, min_m, max_m]},
            "geometricError": e0_m,
            "refine": "REPLACE",
            "content": {"uri": format!("{root}/{{level}}/{{x}}/{{y}}.glb")},
            "implicitTiling": {
                "subdivisionScheme": "QUADTREE",
                "subtreeLevels": levels,
                "availableLevels": u32::from(max_zoom) + 1,
                "subtrees": {"uri": format!("{root}/subtrees/{{level}}/{{x}}/{{y}}.subtree")},
            },
        })
    };
    json!({
        "asset": {"version": "1.1", "generator": "cota"},
        "geometricError": 2.0 * e0_m,
        "schema": schema(),
        "root": {
            "boundingVolume": {"region": [-PI, -FRAC_PI_2, PI, FRAC_PI_2, min_m, max_m]},
            "geometricError": 2.0 * e0_m,
            "refine": "REPLACE",
            "children": [child(0), child(1)],
        },
    })
}

/// Spreads the bits of `v` to the even positions.
fn spread(v: u32) -> u64 {
    let mut x = u64::from(v);
    x = (x | (x << 16)) & 0x0000_FFFF_0000_FFFF;
    x = (x | (x << 8)) & 0x00FF_00FF_00FF_00FF;
    x = (x | (x << 4)) & 0x0F0F_0F0F_0F0F_0F0F;
    x = (x | (x << 2)) & 0x3333_3333_3333_3333;
    (x | (x << 1)) & 0x5555_5555_5555_5555
}

/// Morton index of `(x, y)`: x in the even bits, y in the odd.
fn morton(x: u32, y: u32) -> u64 {
    spread(x) | (spread(y) << 1)
}

/// A subtree's root: implicit root, level, column and row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SubtreeId {
    /// 0 west, 1 east.
    pub root: u32,
    /// Level of its top tile.
    pub level: u8,
    /// Column within the root.
    pub x: u32,
    /// Row from the south.
    pub y: u32,
}

impl SubtreeId {
    /// Its path relative to the output.
    pub fn rel_path(&self) -> String {
        format!(
            "{}/subtrees/{}/{}/{}.subtree",
            self.root, self.level, self.x, self.y
        )
    }

    /// The global tile at local level `l`, column and row `(lx, ly)`.
    fn tile(&self, l: u8, lx: u32, ly: u32) -> TileId {
        let z = self.level + l;
        TileId {
            z,
            x: (self.root << z) + (self.x << l) + lx,
            y: (self.y << l) + ly,
        }
    }
}

/// The subtrees a pyramid of `tiles` needs: one at each available tile on a
/// level that is a multiple of `levels`.
pub fn subtrees(tiles: &HashMap<TileId, TileMeta>, levels: u8) -> Vec<SubtreeId> {
    let mut out: Vec<SubtreeId> = tiles
        .keys()
        .filter(|t| t.z % levels == 0)
        .map(|&t| {
            let (root, x) = implicit_x(t);
            SubtreeId {
                root,
                level: t.z,
                x,
                y: t.y,
            }
        })
        .collect();
    out.sort_by_key(|s| (s.level, s.root, s.x, s.y));
    out
}

/// Bits, least significant first in each byte.
struct Bits(Vec<u8>, u64);

impl Bits {
    fn new(n: u64) -> Bits {
        Bits(vec![0; n.div_ceil(8) as usize], 0)
    }
    fn set(&mut self, i: u64) {
        self.0[(i / 8) as usize] |= 1 << (i % 8);
        self.1 += 1;
    }
}

/// The binary subtree file of `s` (`levels` levels) over `tiles`.
pub fn subtree_bytes(s: SubtreeId, levels: u8, tiles: &HashMap<TileId, TileMeta>) -> Vec<u8> {
    let n_tiles = ((1u64 << (2 * u32::from(levels))) - 1) / 3;
    let mut avail = Bits::new(n_tiles);
    let mut metas: Vec<TileMeta> = Vec::new();
    for l in 0..levels {
        let side = 1u32 << l;
        let offset = ((1u64 << (2 * u32::from(l))) - 1) / 3;
        let mut found: Vec<(u64, TileMeta)> = (0..side)
            .flat_map(|ly| (0..side).map(move |lx| (lx, ly)))
            .filter_map(|(lx, ly)| tiles.get(&s.tile(l, lx, ly)).map(|m| (morton(lx, ly), *m)))
            .collect();
        found.sort_by_key(|f| f.0);
        for (m, meta) in found {
            avail.set(offset + m);
            metas.push(meta);
        }
    }
    let side = 1u32 << levels;
    let mut children = Bits::new(1u64 << (2 * u32::from(levels)));
    for ly in 0..side {
        for lx in 0..side {
            if tiles.contains_key(&s.tile(levels, lx, ly)) {
                children.set(morton(lx, ly));
            }
        }
    }
    encode_subtree(&avail, &children, &metas)
}

/// The subtree's JSON and binary body.
fn encode_subtree(avail: &Bits, children: &Bits, metas: &[TileMeta]) -> Vec<u8> {
    let mut body: Vec<u8> = Vec::new();
    let mut views: Vec<Value> = Vec::new();
    let mut view = |data: &[u8]| {
        while !body.len().is_multiple_of(8) {
            body.push(0);
        }
        views.push(json!({"buffer": 0, "byteOffset": body.len(), "byteLength": data.len()}));
        body.extend_from_slice(data);
        views.len() - 1
    };
    let tile_bits = view(&avail.0);
    let content_bits = view(&avail.0);
    let child_bits = view(&children.0);
    let f64s = |f: &dyn Fn(&TileMeta) -> Vec<f64>| -> Vec<u8> {
        metas
            .iter()
            .flat_map(f)
            .flat_map(f64::to_le_bytes)
            .collect()
    };
    let min = view(&f64s(&|m| vec![m.min_height_m]));
    let max = view(&f64s(&|m| vec![m.max_height_m]));
    let sphere = view(&f64s(&|m| m.sphere.to_vec()));
    let hop = view(&f64s(&|m| m.horizon_occlusion_point.to_vec()));
    while !body.len().is_multiple_of(8) {
        body.push(0);
    }
    let doc = json!({
        "buffers": [{"byteLength": body.len()}],
        "bufferViews": views,
        "tileAvailability": {"bitstream": tile_bits, "availableCount": avail.1},
        "contentAvailability": [{"bitstream": content_bits, "availableCount": avail.1}],
        "childSubtreeAvailability": {"bitstream": child_bits, "availableCount": children.1},
        "propertyTables": [{"class": "tile", "count": metas.len(), "properties": {
            "minimumHeight": {"values": min},
            "maximumHeight": {"values": max},
            "boundingSphere": {"values": sphere},
            "horizonOcclusionPoint": {"values": hop},
        }}],
        "tileMetadata": 0,
    });
    let mut text = doc.to_string().into_bytes();
    while !text.len().is_multiple_of(8) {
        text.push(b' ');
    }
    let mut out = Vec::with_capacity(24 + text.len() + body.len());
    out.extend_from_slice(b"subt");
    out.extend_from_slice(&1u32.to_le_bytes());
    out.extend_from_slice(&(text.len() as u64).to_le_bytes());
    out.extend_from_slice(&(body.len() as u64).to_le_bytes());
    out.extend_from_slice(&text);
    out.extend_from_slice(&body);
    out
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn morton_interleaves_x_in_the_low_bit() {
        assert_eq!(morton(1, 0), 1);
        assert_eq!(morton(0, 1), 2);
        assert_eq!(morton(3, 3), 15);
        assert_eq!(morton(2, 0), 4);
    }

    #[test]
    fn subtree_layers_are_even() {
        assert_eq!(subtree_levels(0), 1);
        assert_eq!(subtree_levels(7), 8);
        assert_eq!(subtree_levels(12), 7);
        assert_eq!(subtree_levels(20), 7);
    }

    #[test]
    fn subtree_marks_the_tiles_and_their_children() {
        let meta = TileMeta {
            min_height_m: 0.0,
            max_height_m: 1.0,
            sphere: [0.0; 4],
            horizon_occlusion_point: [f64::NAN; 3],
        };
        let mut tiles = HashMap::new();
        for t in [(0, 1, 0), (1, 3, 1), (2, 7, 2)] {
            tiles.insert(
                TileId {
                    z: t.0,
                    x: t.1,
                    y: t.2,
                },
                meta,
            );
        }
        let s = SubtreeId {
            root: 1,
            level: 0,
            x: 0,
            y: 0,
        };
        let b = subtree_bytes(s, 2, &tiles);
        assert_eq!(&b[..4], b"subt");
        let json_len = u64::from_le_bytes(b[8..16].try_into().unwrap()) as usize;
        let doc: Value = serde_json::from_slice(&b[24..24 + json_len]).unwrap();
        assert_eq!(doc["tileAvailability"]["availableCount"], 2);
        assert_eq!(doc["childSubtreeAvailability"]["availableCount"], 1);
        let body = &b[24 + json_len..];
        // Level 0 bit 0; level 1 tile (1, 1): offset 1 + morton 3 = bit 4.
        assert_eq!(body[0], 0b1_0001);
        // Child (3, 2) of level 2: morton 0b1101 = 13.
        let child_view = doc["bufferViews"][2]["byteOffset"].as_u64().unwrap() as usize;
        assert_eq!(body[child_view + 1], 1 << 5);
    }
}
