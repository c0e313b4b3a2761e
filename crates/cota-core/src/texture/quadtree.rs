//! The texture quadtree of paper `004_ab8d08b3e6a5a70a.txt` (§2): an
//! *unrestricted* quadtree over an image, subdivided while the accumulated
//! standard deviation of colour exceeds a tolerance; its leaves are the
//! compressed image.
//!
//! # Geometry
//! The root is the square of side `2^k ≥ max(width, height)` with the image
//! in its top-left corner; a node is an aligned square clipped to the image
//! (so nodes on the right and bottom borders are rectangles), and a node
//! wholly outside the image does not exist. Every node splits into its (up
//! to four) children; unlike the terrain's restricted quadtree, neighbours
//! may differ by any number of levels.
//!
//! # Criterion
//! A node of `n` pixels with channel sums `S_c` and sums of squares `Q_c`
//! has per-channel standard deviation `σ_c = √(n·Q_c − S_c²) / n` (the
//! population deviation; `n·Q_c − S_c²` is computed exactly in integers). The
//! paper's "accumulated standard deviation" is read as the sum over the
//! three channels, `σ_R + σ_G + σ_B`, in 8-bit levels. Top-down (the paper's
//! breadth-first order gives the same tree): a node with
//! `σ_R + σ_G + σ_B > tolerance` that is larger than one pixel splits; any
//! other node is a leaf. A larger tolerance therefore gives a subtree of a
//! smaller one's tree.
//!
//! # Leaves, `D(T)` and `C(T)`, exact
//! * A leaf is **flat colour**: the mean of its pixels per channel, rounded
//!   to the nearest level (halves up). This is the paper's compressed image
//!   ([`TextureExtraction::render`] paints it at the image's resolution).
//! * `D(T) = Σ_pixels Σ_c (c − c_leaf)²`, in levels², the paper's distortion:
//!   per leaf `Q_c − 2·m_c·S_c + n·m_c²` with the integer leaf colour `m_c`,
//!   exact in integers ([`TextureExtraction::distortion`]). A zero tolerance
//!   splits every node that is not of one colour, so `D(T) = 0`.
//! * `C(T)`, [`TextureExtraction::bytes`]: the compressed image's bytes in
//!   the paper's representation — one bit per node of the tree in pre-order
//!   (split or leaf; the children of a split node that lie outside the image
//!   are implied by its size and not coded) rounded up to whole bytes, plus
//!   3 bytes (R, G, B) per leaf. The *texels* of the paper's figures are the
//!   leaves ([`TextureExtraction::leaves`]).
//!
//! # Cost
//! [`TextureQuadtree::build`] sums every level once (`O(n)`, 56 bytes per
//! node of the levels above the pixels: about 19 bytes per pixel);
//! [`TextureQuadtree::extract`] walks the nodes it keeps.

use rayon::prelude::*;

use super::image::RgbImage;

/// The sums of one node: pixel count, per-channel sums and sums of squares.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Stats {
    n: u64,
    sum: [u64; 3],
    sq: [u64; 3],
}

impl Stats {
    fn pixel(p: [u8; 3]) -> Self {
        let v = p.map(u64::from);
        Stats {
            n: 1,
            sum: v,
            sq: v.map(|x| x * x),
        }
    }

    fn add(mut self, o: &Stats) -> Self {
        self.n += o.n;
        for c in 0..3 {
            self.sum[c] += o.sum[c];
            self.sq[c] += o.sq[c];
        }
        self
    }

    /// `σ_R + σ_G + σ_B` in levels (see the module docs).
    fn sigma_sum(&self) -> f64 {
        let n = u128::from(self.n.max(1));
        (0..3)
            .map(|c| {
                let num = n * u128::from(self.sq[c]) - u128::from(self.sum[c]).pow(2);
                (num as f64).sqrt() / n as f64
            })
            .sum()
    }

    /// The leaf colour: the rounded mean of each channel.
    fn mean(&self) -> [u8; 3] {
        let n = self.n.max(1);
        self.sum.map(|s| ((2 * s + n) / (2 * n)).min(255) as u8)
    }

    /// `Σ (c − m_c)²` over the node's pixels and channels, for the colour `m`.
    fn distortion(&self, m: [u8; 3]) -> u64 {
        (0..3)
            .map(|c| {
                let m = i128::from(m[c]);
                let d = i128::from(self.sq[c]) - 2 * m * i128::from(self.sum[c])
                    + i128::from(self.n) * m * m;
                d as u64
            })
            .sum()
    }
}

/// One leaf: a rectangle of pixels and its flat colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Leaf {
    /// Column of the leaf's top-left pixel.
    pub x: u32,
    /// Row of the leaf's top-left pixel.
    pub y: u32,
    /// Width in pixels (the node's side, clipped to the image).
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The leaf's colour: the rounded mean of its pixels.
    pub rgb: [u8; 3],
}

/// The compressed image at one tolerance.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureExtraction {
    /// The tolerance on `σ_R + σ_G + σ_B`, levels.
    pub tolerance: f64,
    /// The leaves, in pre-order (the texels of the paper).
    pub leaves: Vec<Leaf>,
    /// Nodes of the tree kept (leaves and split nodes).
    pub nodes: u64,
    /// `D(T)`, levels² (exact).
    pub distortion: u64,
    /// The image's width and height.
    pub size: [usize; 2],
}

impl TextureExtraction {
    /// `C(T)`, bytes: one bit per node, rounded up, plus 3 per leaf (module docs).
    pub fn bytes(&self) -> u64 {
        self.nodes.div_ceil(8) + 3 * self.leaves.len() as u64
    }

    /// The compressed image at the image's resolution: every pixel the colour
    /// of its leaf.
    pub fn render(&self) -> RgbImage {
        let [w, h] = self.size;
        let mut px = vec![[0u8; 3]; w * h];
        for l in &self.leaves {
            for y in l.y as usize..(l.y + l.height) as usize {
                let row = &mut px[y * w..(y + 1) * w];
                row[l.x as usize..(l.x + l.width) as usize].fill(l.rgb);
            }
        }
        // The size is the image's own, checked when it was made.
        RgbImage::from_valid(w, h, px)
    }
}

/// The texture quadtree of one image: the sums of every node above the
/// pixels, built once; extractions at any tolerance.
#[derive(Debug, Clone)]
pub struct TextureQuadtree<'i> {
    image: &'i RgbImage,
    /// `levels[k−1]`: the nodes of side `2^k`, `ceil(w/2^k) × ceil(h/2^k)`
    /// row-major. Level 0 (the pixels) is the image itself.
    levels: Vec<Vec<Stats>>,
    /// `k` of the root (side `2^k`).
    depth: u32,
}

impl<'i> TextureQuadtree<'i> {
    /// Sums every level of `image`'s quadtree (see the module docs).
    pub fn build(image: &'i RgbImage) -> Self {
        let side = image.width().max(image.height()).next_power_of_two();
        let depth = side.trailing_zeros();
        let mut levels: Vec<Vec<Stats>> = Vec::with_capacity(depth as usize);
        for k in 1..=depth {
            let (w, h) = dims(image, k);
            let below = |x: usize, y: usize| -> Stats {
                match levels.last() {
                    None if x < image.width() && y < image.height() => {
                        Stats::pixel(image.get(x, y))
                    }
                    None => Stats::default(),
                    Some(prev) => {
                        let (pw, ph) = dims(image, k - 1);
                        if x < pw && y < ph {
                            prev[y * pw + x]
                        } else {
                            Stats::default()
                        }
                    }
                }
            };
            let level: Vec<Stats> = (0..w * h)
                .into_par_iter()
                .map(|i| {
                    let (x, y) = (2 * (i % w), 2 * (i / w));
                    [(0, 0), (1, 0), (0, 1), (1, 1)]
                        .iter()
                        .fold(Stats::default(), |s, (dx, dy)| {
                            s.add(&below(x + dx, y + dy))
                        })
                })
                .collect();
            levels.push(level);
        }
        TextureQuadtree {
            image,
            levels,
            depth,
        }
    }

    /// The image.
    pub fn image(&self) -> &'i RgbImage {
        self.image
    }

    /// The sums of node (`x`, `y`) of side `2^k` (inside the image).
    fn stats(&self, k: u32, x: usize, y: usize) -> Stats {
        match k {
            0 => Stats::pixel(self.image.get(x, y)),
            _ => {
                let (w, _) = dims(self.image, k);
                self.levels[k as usize - 1][y * w + x]
            }
        }
    }

    /// The compressed image at `tolerance` levels of `σ_R + σ_G + σ_B` (a
    /// NaN or negative tolerance is taken as 0).
    pub fn extract(&self, tolerance: f64) -> TextureExtraction {
        let tol = if tolerance.is_nan() {
            0.0
        } else {
            tolerance.max(0.0)
        };
        let mut out = TextureExtraction {
            tolerance: tol,
            leaves: Vec::new(),
            nodes: 0,
            distortion: 0,
            size: [self.image.width(), self.image.height()],
        };
        let mut stack = vec![(self.depth, 0usize, 0usize)];
        while let Some((k, x, y)) = stack.pop() {
            out.nodes += 1;
            let s = self.stats(k, x, y);
            if k > 0 && s.sigma_sum() > tol {
                let (w, h) = dims(self.image, k - 1);
                // Pushed in reverse so the walk is NW, NE, SW, SE (pre-order).
                for (dx, dy) in [(1, 1), (0, 1), (1, 0), (0, 0)] {
                    let (cx, cy) = (2 * x + dx, 2 * y + dy);
                    if cx < w && cy < h {
                        stack.push((k - 1, cx, cy));
                    }
                }
                continue;
            }
            let rgb = s.mean();
            out.distortion += s.distortion(rgb);
            let side = 1usize << k;
            let (x0, y0) = (x * side, y * side);
            out.leaves.push(Leaf {
                x: x0 as u32,
                y: y0 as u32,
                width: (side.min(self.image.width() - x0)) as u32,
                height: (side.min(self.image.height() - y0)) as u32,
                rgb,
            });
        }
        out
    }
}

/// Nodes of side `2^k` along each axis.
fn dims(image: &RgbImage, k: u32) -> (usize, usize) {
    let side = 1usize << k;
    (image.width().div_ceil(side), image.height().div_ceil(side))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, reason = "tests")]
mod tests {
    use super::*;

    /// A seeded image with flat patches and noise, `w × h`.
    fn image(w: usize, h: usize) -> RgbImage {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let px = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                if x < w / 2 && y < h / 2 {
                    [10, 200, 30]
                } else {
                    let n = (seed % 40) as u8;
                    [(x * 3) as u8 ^ n, (y * 5) as u8, 100 + n]
                }
            })
            .collect();
        RgbImage::new(w, h, px).unwrap()
    }

    /// Brute force: `D(T)` from the rendered image.
    fn brute_distortion(img: &RgbImage, x: &TextureExtraction) -> u64 {
        let r = x.render();
        img.pixels()
            .iter()
            .zip(r.pixels())
            .map(|(a, b)| {
                (0..3)
                    .map(|c| (i64::from(a[c]) - i64::from(b[c])).pow(2) as u64)
                    .sum::<u64>()
            })
            .sum()
    }

    /// Every pixel is in exactly one leaf.
    fn assert_tiles(img: &RgbImage, x: &TextureExtraction) {
        let mut count = vec![0u8; img.width() * img.height()];
        for l in &x.leaves {
            assert!(l.width >= 1 && l.height >= 1);
            for y in l.y..l.y + l.height {
                for xx in l.x..l.x + l.width {
                    count[y as usize * img.width() + xx as usize] += 1;
                }
            }
        }
        assert!(
            count.iter().all(|&c| c == 1),
            "leaves overlap or leave gaps"
        );
    }

    #[test]
    fn leaves_tile_and_distortion_is_exact() {
        for (w, h) in [(1, 1), (1, 7), (37, 21), (64, 64), (65, 33)] {
            let img = image(w, h);
            let t = TextureQuadtree::build(&img);
            let mut last = (u64::MAX, 0);
            for tol in [0.0, 0.5, 3.0, 10.0, 40.0, 120.0, 1000.0] {
                let x = t.extract(tol);
                assert_tiles(&img, &x);
                assert_eq!(x.distortion, brute_distortion(&img, &x), "{w}x{h} at {tol}");
                assert_eq!(x.bytes(), x.nodes.div_ceil(8) + 3 * x.leaves.len() as u64);
                // Larger tolerances: fewer leaves, no smaller distortion.
                assert!(x.leaves.len() as u64 <= last.0 && x.distortion >= last.1);
                last = (x.leaves.len() as u64, x.distortion);
            }
        }
    }

    #[test]
    fn zero_tolerance_is_lossless() {
        let img = image(50, 30);
        let x = TextureQuadtree::build(&img).extract(0.0);
        assert_eq!(x.distortion, 0);
        assert_eq!(x.render(), img);
        // The flat quarter is one leaf per aligned block, not one per pixel.
        assert!(x.leaves.len() < 50 * 30);
        // A huge tolerance keeps the root alone.
        let one = TextureQuadtree::build(&img).extract(1e9);
        assert_eq!((one.leaves.len(), one.nodes), (1, 1));
    }
}
