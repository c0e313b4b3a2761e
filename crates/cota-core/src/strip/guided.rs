//! Guided growth (step 4 of [`super`]): a greedy strip grown from the
//! hierarchy's order into the unvisited neighbour with the fewest unvisited
//! neighbours (Warnsdorff's rule), restarting near the last vertex. Strip
//! vocabulary after Evans, Skiena & Varshney (1996); the order is that of
//! papers `000_ebf7e3a88dffd361.txt` §4 and `001_49f2c365e8c41172.txt`.

use super::emit::{continue_run, finish, start_run, Strip, StripSink, Tail};

/// Triangles around each vertex (compressed rows) and the neighbour across
/// each edge.
struct Adjacency {
    fan_start: Vec<u32>,
    fan: Vec<u32>,
    /// Neighbour across edge `(t[k], t[k+1])`, `u32::MAX` for none.
    nb: Vec<[u32; 3]>,
}

impl Adjacency {
    fn new(tris: &[[u32; 3]]) -> Self {
        let nv = tris
            .iter()
            .flatten()
            .map(|&v| v as usize + 1)
            .max()
            .unwrap_or(0);
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
        // The neighbour across (u, v) of a counter-clockwise triangle is the
        // triangle around v holding the directed edge (v, u).
        let nb = tris
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
        Adjacency { fan_start, fan, nb }
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
    let nb = &adj.nb;
    let (fan_start, fan) = (&adj.fan_start, &adj.fan);
    let mut visited = vec![false; order.len()];
    let free = |visited: &[bool], t: u32| t != u32::MAX && !visited[t as usize];
    let free_count = |visited: &[bool], t: u32| -> usize {
        nb[t as usize].iter().filter(|&&x| free(visited, x)).count()
    };
    let across = |t: usize, u: u32, v: u32| -> u32 {
        let tri = order[t];
        (0..3)
            .find(|&k| {
                let (x, y) = (tri[k], tri[(k + 1) % 3]);
                (x == u && y == v) || (x == v && y == u)
            })
            .map_or(u32::MAX, |k| nb[t][k])
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
                        nb[x as usize]
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
                visited[x] = true;
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
            let (lo, hi) = (fan_start[q as usize], fan_start[q as usize + 1]);
            fan[lo as usize..hi as usize]
                .iter()
                .map(|&x| x as usize)
                .filter(|&x| !visited[x])
                .min_by_key(|&x| (free_count(&visited, x as u32), x))
                .map(|x| (x, q))
        });
        let (t, q) = match around_last {
            Some((t, q)) => (t, Some(q)),
            None => {
                while cursor < order.len() && visited[cursor] {
                    cursor += 1;
                }
                if cursor == order.len() {
                    break;
                }
                (cursor, None)
            }
        };
        visited[t] = true;
        // Leave through the edge whose unvisited neighbour has the fewest
        // unvisited neighbours, preferring the edge opposite the last vertex.
        let tri = order[t];
        let exit = (0..3)
            .filter(|&k| free(&visited, nb[t][k]))
            .min_by_key(|&k| {
                let opposite = Some(tri[(k + 2) % 3]) == q;
                (!opposite, free_count(&visited, nb[t][k]))
            })
            .map(|k| order[nb[t][k] as usize]);
        start_run(&mut s, tri, exit);
        cur = Some(t);
    }
    s
}
