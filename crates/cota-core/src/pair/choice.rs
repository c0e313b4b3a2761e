//! Choosing the pair `(M_i, T_j)` of paper `004_ab8d08b3e6a5a70a.txt` §3:
//! minimise `D = α·D(M_i) + β·D(T_j)` subject to `C(M_i) + C(T_j) ≤ C`.
//!
//! * [`greedy`]: the paper's scan. Both lists sorted by decreasing memory;
//!   for each mesh `i` in that order, for each texture `j` in that order
//!   *while `C(M_i) ≤ C(T_j)`* (the pseudo-code's loop condition), the first
//!   pair with `C(M_i) + C(T_j) ≤ C` is returned. It looks at no distortion:
//!   it bets that more memory means less distortion, and it may find no pair
//!   where one exists (every fitting texture smaller than its mesh).
//! * [`optimum`]: the exact minimum of `D` over all pairs that fit. Without
//!   the elements rule it sorts the textures by memory, keeps the prefix
//!   minimum of `β·D(T)`, and for each mesh finds by binary search the
//!   largest texture that fits: `O((m + t)·log t)`. With the elements rule
//!   (a second constraint) it tries every pair, `O(m·t)`.
//! * [`PairOptions::polygons_within_texels`]: the paper's text advises
//!   against meshes with more polygons than the texture has elements; when
//!   set, a pair is feasible only if `triangles(M_i) ≤ elements(T_j)`, for
//!   both the greedy and the optimum. Default: off.
//!
//! Ties in `D` go to the pair with fewer bytes, then to the lower indices.
//! The distortions are in their own units (m² for meshes, levels² for
//! textures); `α` and `β` weigh them (both 1 by default, the plain sum).

/// One approximation of either list: its memory, distortion and element
/// count (triangles of a mesh, leaves of a texture).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// `C`, bytes (in the caller's stated byte model).
    pub bytes: u64,
    /// `D`, in the list's own units (m² or levels²).
    pub distortion: f64,
    /// Triangles (meshes) or leaves (textures).
    pub elements: u64,
}

/// Options of the choice.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct PairOptions {
    /// Weight of `D(M)`. Default: 1.
    pub alpha: f64,
    /// Weight of `D(T)`. Default: 1.
    pub beta: f64,
    /// Only pairs whose mesh has at most as many triangles as the texture
    /// has leaves (the paper's advice). Default: false.
    pub polygons_within_texels: bool,
}

impl PairOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: PairOptions = PairOptions {
        alpha: 1.0,
        beta: 1.0,
        polygons_within_texels: false,
    };

    /// Sets [`PairOptions::alpha`] and [`PairOptions::beta`].
    pub const fn with_weights(mut self, alpha: f64, beta: f64) -> Self {
        self.alpha = alpha;
        self.beta = beta;
        self
    }

    /// Sets [`PairOptions::polygons_within_texels`].
    pub const fn with_polygons_within_texels(mut self, yes: bool) -> Self {
        self.polygons_within_texels = yes;
        self
    }

    fn feasible(&self, m: &Candidate, t: &Candidate, budget: u64) -> bool {
        m.bytes.saturating_add(t.bytes) <= budget
            && (!self.polygons_within_texels || m.elements <= t.elements)
    }

    fn value(&self, m: &Candidate, t: &Candidate) -> f64 {
        self.alpha * m.distortion + self.beta * t.distortion
    }
}

impl Default for PairOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A chosen pair: indices into the mesh and texture lists as given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pair {
    /// Index of the mesh.
    pub mesh: usize,
    /// Index of the texture.
    pub texture: usize,
    /// `C(M) + C(T)`, bytes.
    pub bytes: u64,
    /// `α·D(M) + β·D(T)`.
    pub distortion: f64,
}

impl Pair {
    fn of(m: &[Candidate], t: &[Candidate], i: usize, j: usize, o: &PairOptions) -> Pair {
        Pair {
            mesh: i,
            texture: j,
            bytes: m[i].bytes + t[j].bytes,
            distortion: o.value(&m[i], &t[j]),
        }
    }

    /// True when `self` is a better pair than `other` (smaller `D`, then
    /// fewer bytes, then lower indices).
    fn better_than(&self, other: &Pair) -> bool {
        let key = |p: &Pair| (p.distortion, p.bytes, p.mesh, p.texture);
        key(self).partial_cmp(&key(other)) == Some(std::cmp::Ordering::Less)
    }
}

/// Why no pair was chosen.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PairError {
    /// A list is empty.
    #[error(
        "expected at least one mesh and one texture, found {meshes} meshes and {textures} textures"
    )]
    EmptyList {
        /// Meshes given.
        meshes: usize,
        /// Textures given.
        textures: usize,
    },
    /// A weight is negative or not finite.
    #[error("expected finite weights of 0 or more, found alpha {alpha}, beta {beta}")]
    BadWeights {
        /// α.
        alpha: f64,
        /// β.
        beta: f64,
    },
    /// No pair fits the budget.
    #[error("expected a budget of at least {smallest} bytes (the smallest feasible pair), found {budget}")]
    NothingFits {
        /// The budget.
        budget: u64,
        /// Bytes of the smallest feasible pair (`u64::MAX` when the
        /// elements rule admits none at all).
        smallest: u64,
    },
}

/// Both choices at one budget.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Choice {
    /// The exact optimum.
    pub optimum: Pair,
    /// The paper's greedy scan, `None` when it finds no pair.
    pub greedy: Option<Pair>,
}

impl Choice {
    /// `D(greedy) − D(optimum)` (≥ 0), `None` when the greedy found none.
    pub fn gap(&self) -> Option<f64> {
        self.greedy.map(|g| g.distortion - self.optimum.distortion)
    }
}

/// The optimum and the greedy at `budget` bytes.
///
/// # Errors
/// [`PairError::EmptyList`], [`PairError::BadWeights`],
/// [`PairError::NothingFits`] with the smallest feasible budget.
pub fn choose(
    meshes: &[Candidate],
    textures: &[Candidate],
    budget: u64,
    opts: &PairOptions,
) -> Result<Choice, PairError> {
    if meshes.is_empty() || textures.is_empty() {
        return Err(PairError::EmptyList {
            meshes: meshes.len(),
            textures: textures.len(),
        });
    }
    let w = [opts.alpha, opts.beta];
    if !w.iter().all(|x| x.is_finite() && *x >= 0.0) {
        return Err(PairError::BadWeights {
            alpha: opts.alpha,
            beta: opts.beta,
        });
    }
    let Some(best) = optimum(meshes, textures, budget, opts) else {
        return Err(PairError::NothingFits {
            budget,
            smallest: smallest_feasible(meshes, textures, opts),
        });
    };
    Ok(Choice {
        optimum: best,
        greedy: greedy(meshes, textures, budget, opts),
    })
}

/// The fewest bytes of any pair the elements rule admits.
fn smallest_feasible(meshes: &[Candidate], textures: &[Candidate], opts: &PairOptions) -> u64 {
    let mut best = u64::MAX;
    for m in meshes {
        for t in textures {
            if opts.feasible(m, t, u64::MAX) {
                best = best.min(m.bytes.saturating_add(t.bytes));
            }
        }
    }
    best
}

/// Indices of `list` by decreasing bytes (ties: smaller distortion first,
/// then index).
fn by_decreasing_bytes(list: &[Candidate]) -> Vec<usize> {
    let mut ix: Vec<usize> = (0..list.len()).collect();
    ix.sort_by(|&a, &b| {
        let (x, y) = (&list[a], &list[b]);
        y.bytes
            .cmp(&x.bytes)
            .then(x.distortion.total_cmp(&y.distortion))
            .then(a.cmp(&b))
    });
    ix
}

/// The paper's greedy scan (module docs); `None` when it finds no pair.
pub fn greedy(
    meshes: &[Candidate],
    textures: &[Candidate],
    budget: u64,
    opts: &PairOptions,
) -> Option<Pair> {
    let tex = by_decreasing_bytes(textures);
    for i in by_decreasing_bytes(meshes) {
        let m = &meshes[i];
        for &j in tex.iter().take_while(|&&j| m.bytes <= textures[j].bytes) {
            if opts.feasible(m, &textures[j], budget) {
                return Some(Pair::of(meshes, textures, i, j, opts));
            }
        }
    }
    None
}

/// The exact optimum over every pair that fits (module docs); `None` when
/// none does.
pub fn optimum(
    meshes: &[Candidate],
    textures: &[Candidate],
    budget: u64,
    opts: &PairOptions,
) -> Option<Pair> {
    if opts.polygons_within_texels {
        return exhaustive(meshes, textures, budget, opts);
    }
    // Textures by increasing bytes, and the best one (by β·D(T), then
    // bytes, then index) among the first k for every k.
    let mut tex: Vec<usize> = (0..textures.len()).collect();
    tex.sort_by_key(|&j| (textures[j].bytes, j));
    let key = |j: usize| (opts.beta * textures[j].distortion, textures[j].bytes, j);
    let mut prefix: Vec<usize> = Vec::with_capacity(tex.len());
    for &j in &tex {
        let keep = match prefix.last() {
            Some(&b) if key(b).partial_cmp(&key(j)) != Some(std::cmp::Ordering::Greater) => b,
            _ => j,
        };
        prefix.push(keep);
    }
    let mut best: Option<Pair> = None;
    for (i, m) in meshes.iter().enumerate() {
        let Some(room) = budget.checked_sub(m.bytes) else {
            continue;
        };
        let fit = tex.partition_point(|&j| textures[j].bytes <= room);
        let Some(&j) = fit.checked_sub(1).map(|k| &prefix[k]) else {
            continue;
        };
        let p = Pair::of(meshes, textures, i, j, opts);
        if best.is_none_or(|b| p.better_than(&b)) {
            best = Some(p);
        }
    }
    best
}

/// Every pair tried: the optimum with any feasibility rule.
fn exhaustive(
    meshes: &[Candidate],
    textures: &[Candidate],
    budget: u64,
    opts: &PairOptions,
) -> Option<Pair> {
    let mut best: Option<Pair> = None;
    for (i, m) in meshes.iter().enumerate() {
        for (j, t) in textures.iter().enumerate() {
            if !opts.feasible(m, t, budget) {
                continue;
            }
            let p = Pair::of(meshes, textures, i, j, opts);
            if best.is_none_or(|b| p.better_than(&b)) {
                best = Some(p);
            }
        }
    }
    best
}

#[cfg(test)]
#[allow(clippy::unwrap_used, reason = "tests")]
mod tests {
    use super::*;

    /// Lists shaped like real ones: more bytes, less distortion, with noise
    /// (seeded), so that the greedy is not always right.
    fn lists(seed: u64, m: usize, t: usize) -> (Vec<Candidate>, Vec<Candidate>) {
        let mut s = seed | 1;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let mut make = |n: usize, scale: f64| {
            (0..n)
                .map(|k| {
                    let bytes = 1000 + (k as u64 + 1) * 3000 + next() % 2500;
                    Candidate {
                        bytes,
                        distortion: scale * 1e9 / bytes as f64
                            * (0.5 + (next() % 1000) as f64 / 1000.0),
                        elements: bytes / 12 + next() % 100,
                    }
                })
                .collect::<Vec<_>>()
        };
        (make(m, 3.0), make(t, 1.0))
    }

    #[test]
    fn optimum_is_the_exhaustive_minimum_and_greedy_is_feasible() {
        for seed in 1..40u64 {
            let (ms, ts) = lists(seed, 1 + (seed as usize % 13), 1 + (seed as usize % 9));
            for opts in [
                PairOptions::DEFAULT,
                PairOptions::DEFAULT.with_weights(0.2, 3.0),
                PairOptions::DEFAULT.with_polygons_within_texels(true),
            ] {
                for budget in (0..60).map(|k| k * 1500) {
                    let fast = optimum(&ms, &ts, budget, &opts);
                    let slow = exhaustive(&ms, &ts, budget, &opts);
                    assert_eq!(fast, slow, "seed {seed} budget {budget}");
                    if let Some(g) = greedy(&ms, &ts, budget, &opts) {
                        assert!(g.bytes <= budget);
                        assert!(opts.feasible(&ms[g.mesh], &ts[g.texture], budget));
                        assert!(g.distortion >= slow.unwrap().distortion);
                    }
                }
            }
        }
    }

    #[test]
    fn greedy_follows_the_papers_scan() {
        // Meshes 9000 and 4000 bytes, textures 10000, 5000, 3000.
        let c = |bytes, distortion| Candidate {
            bytes,
            distortion,
            elements: 0,
        };
        let ms = [c(4000, 50.0), c(9000, 1.0)];
        let ts = [c(3000, 30.0), c(10_000, 1.0), c(5000, 20.0)];
        // 14 000: mesh 9000 with texture 10 000 does not fit and 5000 < 9000
        // stops the inner loop; mesh 4000 with texture 10 000 fits (D = 51),
        // while 9000 + 5000 (D = 21) was never tried.
        let g = greedy(&ms, &ts, 14_000, &PairOptions::DEFAULT).unwrap();
        assert_eq!((g.mesh, g.texture), (0, 1));
        let best = optimum(&ms, &ts, 14_000, &PairOptions::DEFAULT).unwrap();
        assert_eq!((best.mesh, best.texture, best.distortion), (1, 2, 21.0));
        // 12 000: mesh 9000 fits only with 3000 < 9000, so the scan moves to
        // mesh 4000 and takes texture 5000 (10 000 does not fit).
        let g = greedy(&ms, &ts, 12_000, &PairOptions::DEFAULT).unwrap();
        assert_eq!((g.mesh, g.texture), (0, 2));
        let c12 = choose(&ms, &ts, 12_000, &PairOptions::DEFAULT).unwrap();
        assert_eq!((c12.optimum.mesh, c12.optimum.texture), (1, 0)); // 1 + 30 < 50 + 20
        assert_eq!(c12.gap(), Some(39.0));
        // 7000: only 4000 + 3000 fits, and 3000 < 4000 stops the greedy.
        assert_eq!(greedy(&ms, &ts, 7000, &PairOptions::DEFAULT), None);
        let e = choose(&ms, &ts, 6999, &PairOptions::DEFAULT).unwrap_err();
        assert_eq!(
            e,
            PairError::NothingFits {
                budget: 6999,
                smallest: 7000
            }
        );
        assert!(matches!(
            choose(
                &ms,
                &ts,
                1 << 20,
                &PairOptions::DEFAULT.with_weights(-1.0, 1.0)
            ),
            Err(PairError::BadWeights { .. })
        ));
    }
}
