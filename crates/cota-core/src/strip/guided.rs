//! Guided growth (step 4 of [`super`]): a greedy strip grown from the
//! hierarchy's order into the unvisited neighbour with the fewest unvisited
//! neighbours (Warnsdorff's rule), restarting near the last vertex. Strip
//! vocabulary after Evans, Skiena & Varshney (1996); the order is that of
//! papers `000_ebf7e3a88dffd361.txt` §4 and `001_49f2c365e8c41172.txt`.

use rustc_hash::FxHashMap;

use super::emit::{continue_run, finish, start_run, Strip, StripSink, Tail};

/// The neighbour across each edge, and the triangles around each vertex.
struct Adjacency {
    /// Neighbour across edge `(t[k], t[k+1])`, `u32::MAX` for none: the
    /// first triangle (in order) holding the directed edge `(t[k+1], t[k])`.
    nb: Neighbours,
    fans: Fans,
}

/// The neighbours, each stored as its distance in the order when that
/// fits in 16 bits (in a locality order nearly all do), else in a map:
/// 6 bytes per triangle instead of 12.
struct Neighbours {
    near: Vec<[i16; 3]>,
    far: FxHashMap<u64, u32>,
}

impl Neighbours {
    /// No neighbour (a triangle is not its own).
    const NONE: i16 = 0;
    /// The neighbour is in `far`.
    const FAR: i16 = i16::MIN;

    fn new(n: usize) -> Self {
        Neighbours {
            near: vec![[Neighbours::NONE; 3]; n],
            far: FxHashMap::default(),
        }
    }

    fn set(&mut self, t: usize, k: usize, x: u32) {
        let d = i64::from(x) - t as i64;
        if x == u32::MAX {
            self.near[t][k] = Neighbours::NONE;
        } else if d != 0 && d > i64::from(Neighbours::FAR) && d <= i64::from(i16::MAX) {
            self.near[t][k] = d as i16;
        } else {
            self.near[t][k] = Neighbours::FAR;
            self.far.insert(3 * t as u64 + k as u64, x);
        }
    }

    /// The neighbours of triangle `t` across its 3 edges.
    #[inline]
    fn of(&self, t: usize) -> [u32; 3] {
        let near = self.near[t];
        [0, 1, 2].map(|k| match near[k] {
            Neighbours::NONE => u32::MAX,
            Neighbours::FAR => self.far[&(3 * t as u64 + k as u64)],
            d => (t as i64 + i64::from(d)) as u32,
        })
    }

    fn from_rows(rows: &[[u32; 3]]) -> Self {
        let mut nb = Neighbours::new(rows.len());
        for (t, r) in rows.iter().enumerate() {
            for (k, &x) in r.iter().enumerate() {
                nb.set(t, k, x);
            }
        }
        nb
    }
}

/// The triangles around each vertex.
enum Fans {
    /// Compressed rows: the triangles around vertex `v` are
    /// `fan[fan_start[v]..fan_start[v + 1]]`.
    Rows { fan_start: Vec<u32>, fan: Vec<u32> },
    /// Walked across [`Adjacency::nb`] from the first triangle around each
    /// vertex (`u32::MAX`: none), where that walk finds them all; the fans
    /// of the other vertices (flagged [`ODD`] in `degree`) kept whole.
    Walked {
        first: Vec<u32>,
        degree: Vec<u8>,
        odd: FxHashMap<u32, Vec<u32>>,
    },
}

/// [`Fans::Walked`]'s degree of a vertex whose fan is kept whole, or which
/// is in 255 or more triangles.
const ODD: u8 = u8::MAX;

impl Adjacency {
    /// The adjacency of `tris`. For a mesh where no directed edge is held
    /// twice and no triangle repeats a vertex (every oriented conforming or
    /// faithful mesh), the neighbours are matched along the order with
    /// only the edges of unfinished vertices in memory, and the fans are
    /// walked: 6 bytes per triangle (and a few in a map) and 5 per vertex
    /// instead of 24 and 8. Any other input gets the compressed rows; both give the same
    /// neighbours and the same fans (as sets).
    fn new(tris: &[[u32; 3]]) -> Self {
        let nv = tris
            .iter()
            .flatten()
            .map(|&v| v as usize + 1)
            .max()
            .unwrap_or(0);
        Adjacency::matched(tris, nv).unwrap_or_else(|| Adjacency::rows(tris, nv))
    }

    /// Triangles around each vertex as compressed rows, and the
    /// neighbours found in them.
    fn rows(tris: &[[u32; 3]], nv: usize) -> Self {
        let mut fan_start = vec![0u32; nv + 1];
        for &v in tris.iter().flatten() {
            fan_start[v as usize + 1] += 1;
        }
        for i in 0..nv {
            fan_start[i + 1] += fan_start[i];
        }
        let mut fill = fan_start.clone();
        let mut fan = vec![0u32; tris.len() * 3];
        for (i, t) in tris.iter().enumerate() {
            for &v in t {
                fan[fill[v as usize] as usize] = i as u32;
                fill[v as usize] += 1;
            }
        }
        drop(fill);
        // The neighbour across (u, v) of a counter-clockwise triangle is the
        // triangle around v holding the directed edge (v, u).
        let nb: Vec<[u32; 3]> = tris
            .iter()
            .map(|t| {
                [0, 1, 2].map(|k| {
                    let (u, v) = (t[k], t[(k + 1) % 3]);
                    let (lo, hi) = (fan_start[v as usize], fan_start[v as usize + 1]);
                    fan[lo as usize..hi as usize]
                        .iter()
                        .copied()
                        .find(|&x| {
                            let o = tris[x as usize];
                            (0..3).any(|r| o[r] == v && o[(r + 1) % 3] == u)
                        })
                        .unwrap_or(u32::MAX)
                })
            })
            .collect();
        Adjacency {
            nb: Neighbours::from_rows(&nb),
            fans: Fans::Rows { fan_start, fan },
        }
    }

    /// Neighbours matched along the order and walked fans (see
    /// [`Adjacency::new`]); `None` when a directed edge is held twice or a
    /// triangle repeats a vertex.
    fn matched(tris: &[[u32; 3]], nv: usize) -> Option<Self> {
        if tris
            .iter()
            .any(|t| t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
        {
            return None;
        }
        let mut degree = vec![0u8; nv];
        for &v in tris.iter().flatten() {
            degree[v as usize] = degree[v as usize].saturating_add(1);
        }
        let nb = match_along(tris, &degree)?;
        Some(Adjacency::walked(tris, nb, degree))
    }

    /// The fans walked across `nb`, the vertices where a walk misses part
    /// of the fan (T-junctions, pinched fans) keeping theirs whole.
    fn walked(tris: &[[u32; 3]], nb: Neighbours, degree: Vec<u8>) -> Self {
        let nv = degree.len();
        let mut first = vec![u32::MAX; nv];
        for (i, t) in tris.iter().enumerate() {
            for &v in t {
                if first[v as usize] == u32::MAX {
                    first[v as usize] = i as u32;
                }
            }
        }
        let mut adj = Adjacency {
            nb,
            fans: Fans::Walked {
                first,
                degree,
                odd: FxHashMap::default(),
            },
        };
        let mut odd: FxHashMap<u32, Vec<u32>> = FxHashMap::default();
        let mut buf = Vec::new();
        for q in 0..nv as u32 {
            if !adj.walk(tris, q, &mut buf) {
                odd.insert(q, Vec::new());
            }
        }
        if !odd.is_empty() {
            for (i, t) in tris.iter().enumerate() {
                for &v in t {
                    if let Some(f) = odd.get_mut(&v) {
                        f.push(i as u32);
                    }
                }
            }
        }
        if let Fans::Walked { degree, odd: o, .. } = &mut adj.fans {
            for &q in odd.keys() {
                degree[q as usize] = ODD;
            }
            *o = odd;
        }
        adj
    }

    /// Walks around `q` across the neighbours, into `out`: true when the
    /// walk found its whole fan (as many distinct triangles as `q` is in).
    fn walk(&self, tris: &[[u32; 3]], q: u32, out: &mut Vec<u32>) -> bool {
        out.clear();
        let Fans::Walked { first, degree, .. } = &self.fans else {
            return false;
        };
        let (start, degree) = (first[q as usize], degree[q as usize]);
        if start == u32::MAX {
            return true;
        }
        if degree == ODD {
            return false;
        }
        let corner = |t: u32| tris[t as usize].iter().position(|&v| v == q);
        out.push(start);
        // Counter-clockwise across (q, next) until back at the start or at
        // an edge without a neighbour, then clockwise across (prev, q).
        let mut closed = false;
        for step in [0, 2] {
            let mut t = start;
            while !closed {
                if out.len() > usize::from(degree) {
                    return false;
                }
                let Some(r) = corner(t) else {
                    return false;
                };
                let n = self.nb.of(t as usize)[(r + step) % 3];
                if n == u32::MAX {
                    break;
                }
                if n == start {
                    closed = true;
                    break;
                }
                out.push(n);
                t = n;
            }
        }
        if out.len() != usize::from(degree) {
            return false;
        }
        let mut sorted = out.clone();
        sorted.sort_unstable();
        sorted.windows(2).all(|w| w[0] != w[1])
    }

    /// Calls `f` with each triangle around `q` (once each, in no set order).
    fn around(&self, tris: &[[u32; 3]], q: u32, buf: &mut Vec<u32>, mut f: impl FnMut(u32)) {
        match &self.fans {
            Fans::Rows { fan_start, fan } => {
                let (lo, hi) = (fan_start[q as usize], fan_start[q as usize + 1]);
                fan[lo as usize..hi as usize].iter().for_each(|&x| f(x));
            }
            Fans::Walked { odd, .. } => {
                if let Some(whole) = odd.get(&q) {
                    whole.iter().for_each(|&x| f(x));
                } else {
                    self.walk(tris, q, buf);
                    buf.iter().for_each(|&x| f(x));
                }
            }
        }
    }
}

/// The neighbours of `tris` (see [`Adjacency::new`]), matched along the
/// order with only the directed edges of unfinished vertices (by `degree`,
/// [`ODD`] never finished) in memory; `None` when a directed edge is held
/// twice.
fn match_along(tris: &[[u32; 3]], degree: &[u8]) -> Option<Neighbours> {
    // Triangles still to come around each vertex (ODD: never finished).
    let mut left = degree.to_vec();
    let key = |u: u32, v: u32| (u64::from(u) << 32) | u64::from(v);
    // Directed edges of unfinished vertices: their triangle, and
    // whether their twin was found.
    let mut open: FxHashMap<u64, (u32, bool)> = FxHashMap::default();
    let mut swept = 1024usize;
    let mut nb = Neighbours::new(tris.len());
    for (i, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            let twin = match open.get_mut(&key(v, u)) {
                Some((j, matched)) if !*matched => {
                    *matched = true;
                    Some(*j)
                }
                // Its twin taken: (u, v) is held twice.
                Some(_) => return None,
                None => None,
            };
            if open.insert(key(u, v), (i as u32, twin.is_some())).is_some() {
                return None;
            }
            if let Some(j) = twin {
                nb.set(i, k, j);
                let o = tris[j as usize];
                let r = (0..3).find(|&r| o[r] == v && o[(r + 1) % 3] == u)?;
                nb.set(j as usize, r, i as u32);
            }
        }
        for &v in t {
            let l = &mut left[v as usize];
            if *l != ODD {
                *l -= 1;
            }
        }
        // No later triangle holds an edge of a finished vertex.
        if open.len() > 2 * swept {
            open.retain(|&e, _| left[(e >> 32) as usize] != 0 && left[e as u32 as usize] != 0);
            swept = open.len().max(1024);
        }
    }
    Some(nb)
}

/// One bit per triangle.
struct Bits(Vec<u64>);

impl Bits {
    fn new(n: usize) -> Self {
        Bits(vec![0; n.div_ceil(64)])
    }
    #[inline]
    fn get(&self, i: usize) -> bool {
        self.0[i / 64] & (1 << (i % 64)) != 0
    }
    #[inline]
    fn set(&mut self, i: usize) {
        self.0[i / 64] |= 1 << (i % 64);
    }
}

/// Strips triangles (counter-clockwise) given in a locality order, the
/// hierarchy's for [`super::StripMethod::Guided`]: step 4 of the module docs (both
/// tie rules, the shorter strip).
pub(crate) fn stripify_guided(order: &[[u32; 3]]) -> Strip {
    let adj = Adjacency::new(order);
    let capacity = order.len() * 3 / 2 + 8;
    let (plain, ahead) = rayon::join(
        || grow(order, &adj, false, Vec::with_capacity(capacity)),
        || grow(order, &adj, true, Vec::with_capacity(capacity)),
    );
    finish(if ahead.len() < plain.len() {
        ahead
    } else {
        plain
    })
}

/// [`stripify_guided`]'s references, counted without writing the strip.
pub(crate) fn guided_refs(order: &[[u32; 3]]) -> usize {
    let adj = Adjacency::new(order);
    let (plain, ahead) = rayon::join(
        || grow(order, &adj, false, Tail::default()),
        || grow(order, &adj, true, Tail::default()),
    );
    plain.len().min(ahead.len())
}

/// One greedy growth into `s`; `lookahead` breaks ties between the natural
/// and the swap neighbour by the unvisited neighbours of their unvisited
/// neighbours.
fn grow<S: StripSink>(order: &[[u32; 3]], adj: &Adjacency, lookahead: bool, mut s: S) -> S {
    let nb = |t: usize| adj.nb.of(t);
    let mut visited = Bits::new(order.len());
    let mut fan = Vec::new();
    let free = |visited: &Bits, t: u32| t != u32::MAX && !visited.get(t as usize);
    let free_count = |visited: &Bits, t: u32| -> usize {
        nb(t as usize).iter().filter(|&&x| free(visited, x)).count()
    };
    let across = |t: usize, u: u32, v: u32| -> u32 {
        let tri = order[t];
        (0..3)
            .find(|&k| {
                let (x, y) = (tri[k], tri[(k + 1) % 3]);
                (x == u && y == v) || (x == v && y == u)
            })
            .map_or(u32::MAX, |k| nb(t)[k])
    };
    let mut cursor = 0usize;
    let mut cur: Option<usize> = None;
    loop {
        if let Some(t) = cur {
            let (o, p, q) = (s.back(2), s.back(1), s.back(0));
            let nat = across(t, p, q);
            let swp = across(t, o, q);
            let nat_ok = free(&visited, nat);
            let swp_ok = free(&visited, swp);
            let pick = match (nat_ok, swp_ok) {
                (true, true) => {
                    let second = |x: u32| -> usize {
                        nb(x as usize)
                            .iter()
                            .filter(|&&y| free(&visited, y))
                            .map(|&y| free_count(&visited, y))
                            .sum()
                    };
                    let (cn, cs) = (free_count(&visited, nat), free_count(&visited, swp));
                    let (sn, ss) = if lookahead && cn == cs {
                        (second(nat), second(swp))
                    } else {
                        (0, 0)
                    };
                    Some(if (cs, ss) < (cn, sn) { swp } else { nat })
                }
                (true, false) => Some(nat),
                (false, true) => Some(swp),
                (false, false) => None,
            };
            if let Some(x) = pick {
                let x = x as usize;
                visited.set(x);
                if !continue_run(&mut s, order[x]) {
                    start_run(&mut s, order[x], None);
                }
                cur = Some(x);
                continue;
            }
        }
        // Restart: an unvisited triangle around the last vertex (one
        // connector index), else the first unvisited one in `order`.
        let around_last = s.last().and_then(|q| {
            let mut best: Option<(usize, usize)> = None;
            adj.around(order, q, &mut fan, |x| {
                let x = x as usize;
                if !visited.get(x) {
                    let k = (free_count(&visited, x as u32), x);
                    if best.is_none_or(|b| k < b) {
                        best = Some(k);
                    }
                }
            });
            best.map(|(_, x)| (x, q))
        });
        let (t, q) = match around_last {
            Some((t, q)) => (t, Some(q)),
            None => {
                while cursor < order.len() && visited.get(cursor) {
                    cursor += 1;
                }
                if cursor == order.len() {
                    break;
                }
                (cursor, None)
            }
        };
        visited.set(t);
        // Leave through the edge whose unvisited neighbour has the fewest
        // unvisited neighbours, preferring the edge opposite the last vertex.
        let tri = order[t];
        let exit = (0..3)
            .filter(|&k| free(&visited, nb(t)[k]))
            .min_by_key(|&k| {
                let opposite = Some(tri[(k + 2) % 3]) == q;
                (!opposite, free_count(&visited, nb(t)[k]))
            })
            .map(|k| order[nb(t)[k] as usize]);
        start_run(&mut s, tri, exit);
        cur = Some(t);
    }
    s
}

/// Whether the matched neighbours and walked fans of `order` are the
/// compressed rows' (`None` when `order` takes the rows anyway).
#[cfg(test)]
pub(super) fn matched_is_rows(order: &[[u32; 3]]) -> Option<bool> {
    let nv = order
        .iter()
        .flatten()
        .map(|&v| v as usize + 1)
        .max()
        .unwrap_or(0);
    let m = Adjacency::matched(order, nv)?;
    let r = Adjacency::rows(order, nv);
    let fans = |a: &Adjacency, q: u32| {
        let mut buf = Vec::new();
        let mut f = Vec::new();
        a.around(order, q, &mut buf, |x| f.push(x));
        f.sort_unstable();
        f
    };
    let same_nb = (0..order.len()).all(|t| m.nb.of(t) == r.nb.of(t));
    Some(same_nb && (0..nv as u32).all(|q| fans(&m, q) == fans(&r, q)))
}
