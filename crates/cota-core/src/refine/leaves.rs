//! The mesh a closed set of marks describes: the marked tree walked top
//! down, fictitious points given their height on the way (the midpoint of
//! their diagonal, paper `000_ebf7e3a88dffd361.txt` §2.2), the leaves
//! numbered row-major as the bitree's extraction numbers them (steps 3 and 5
//! of [`super`]).

use super::marks::Marks;
use crate::grid::HeightGrid;
use crate::hierarchy::{orient_up, walk, Hierarchy, Tri, Visitor};
use crate::mesh::{Mesh, MeshVertex};

/// A leaf of the current mesh.
#[derive(Debug, Clone, Copy)]
pub(super) struct Leaf {
    pub(super) tri: Tri,
    pub(super) depth: u32,
}

/// The walk's visitor: a leaf splits where the marks say, and every
/// fictitious split point gets its mesh height on the way down.
struct Leaves<'m> {
    marks: &'m Marks,
    hier: Hierarchy,
    z: Vec<f32>,
    leaves: Vec<Leaf>,
}

impl Visitor for Leaves<'_> {
    /// The depth, 0 at the roots.
    type Down = u32;
    type Error = std::convert::Infallible;

    fn straddling(&mut self, _t: &Tri, depth: u32) -> Result<u32, Self::Error> {
        Ok(depth + 1)
    }

    fn inside(&mut self, t: &Tri, depth: u32) -> Result<Option<u32>, Self::Error> {
        if !self.marks.splits(t) {
            return Ok(None);
        }
        let m = t.mid();
        if self.marks.is_fictitious(m) {
            let hier = &self.hier;
            let (za, zb) = (
                self.z[hier.index(t.a)] as f64,
                self.z[hier.index(t.b)] as f64,
            );
            self.z[hier.index(m)] = (0.5 * (za + zb)) as f32;
        }
        Ok(Some(depth + 1))
    }

    fn leaf(&mut self, t: &Tri, depth: u32) {
        self.leaves.push(Leaf { tri: *t, depth });
    }
}

/// Walks the marked tree: the leaves inside the grid, and the mesh height of
/// every sample (only vertices' entries are meaningful). The second root's
/// leaves come first (the order of the meshes cota has always written).
pub(super) fn leaves(grid: &HeightGrid, marks: &Marks) -> (Vec<Leaf>, Vec<f32>) {
    let hier = *marks.hierarchy();
    let mut v = Leaves {
        marks,
        hier,
        z: grid.heights().to_vec(),
        leaves: Vec::new(),
    };
    let [r0, r1] = hier.roots();
    let Ok(()) = walk(&hier, &[r1, r0], 0, &mut v);
    (v.leaves, v.z)
}

/// Builds the mesh from the leaves (dropped once their triangles are made);
/// returns it with the counts of real and fictitious vertices.
pub(super) fn emit(
    grid: &HeightGrid,
    marks: &Marks,
    z: &[f32],
    leaves: Vec<Leaf>,
) -> (Mesh, usize, usize) {
    let hier = marks.hierarchy();
    let n = grid.len();
    let mut bits = vec![0u64; n.div_ceil(64)];
    let mut tris = Vec::with_capacity(leaves.len());
    for l in &leaves {
        let t = l.tri;
        let (a, b, c) = if orient_up(t.a, t.b, t.c) > 0 {
            (t.a, t.b, t.c)
        } else {
            (t.b, t.a, t.c)
        };
        let ids = [
            hier.index(a) as u32,
            hier.index(b) as u32,
            hier.index(c) as u32,
        ];
        for &i in &ids {
            bits[(i / 64) as usize] |= 1u64 << (i % 64);
        }
        tris.push(ids);
    }
    drop(leaves);
    let mut prefix = Vec::with_capacity(bits.len());
    let mut total = 0u32;
    for &word in &bits {
        prefix.push(total);
        total += word.count_ones();
    }
    let w = grid.width() as u32;
    let mut vertices = Vec::with_capacity(total as usize);
    let mut fictitious = 0;
    for (k, &word) in bits.iter().enumerate() {
        let mut rest = word;
        while rest != 0 {
            let bit = rest.trailing_zeros();
            rest &= rest - 1;
            let i = k as u32 * 64 + bit;
            let p = [i % w, i / w];
            if marks.is_fictitious(p) {
                fictitious += 1;
            }
            vertices.push(MeshVertex {
                col: p[0],
                row: p[1],
                z_m: z[i as usize],
            });
        }
    }
    for t in &mut tris {
        for i in t.iter_mut() {
            let (word, bit) = ((*i / 64) as usize, *i % 64);
            let below = bits[word] & ((1u64 << bit) - 1);
            *i = prefix[word] + below.count_ones();
        }
    }
    let transmitted = vertices.len() - fictitious;
    (
        Mesh {
            vertices,
            triangles: tris,
        },
        transmitted,
        fictitious,
    )
}
