//! The meshoptimizer index codecs, written from Appendix A of the
//! `EXT_meshopt_compression` specification.
//!
//! Mode `TRIANGLES` (header `0xe1`): one code byte per triangle, then extra
//! data (varint-7 zigzag deltas from `last`, or a byte of two nibbles), then
//! a 16-byte lookup table `codeaux`. The decoder keeps `next` (the next new
//! index), `last`, a FIFO of 16 edges and one of 16 vertices; a triangle is
//! coded from an edge in the FIFO plus a third index (`next`, a FIFO vertex,
//! `last ± 1`, or a delta), or, without such an edge, from three indices
//! (`next`, FIFO vertices, deltas; a table entry when all three fit).
//! This encoder runs the decoder's state itself and picks, for each triangle
//! as given (or, with [`encode_triangles_rotated`], turned to the rotation
//! with a FIFO edge and the cheapest third index), the shortest code; it only reads FIFO entries the decoder has filled. The
//! table holds the 14 most frequent (b, c) nibble pairs of this buffer's
//! FIFO-only triangles.
//!
//! Mode `INDICES` (header `0xd1`): per index a varint-7 of a zigzagged delta
//! (shifted left one bit) from one of two baselines (the low bit), then 4
//! zero bytes. Here each index takes the baseline nearer to it.

use std::collections::HashMap;

use super::MeshoptError;

/// Appends `v` as a varint-7 (LEB128).
fn push_varint(out: &mut Vec<u8>, mut v: u32) {
    while v >= 0x80 {
        out.push((v as u8 & 0x7f) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

/// The 32-bit zigzag code of `x − from` (wrapping).
fn zigzag_delta(x: u32, from: u32) -> u32 {
    let d = x.wrapping_sub(from) as i32;
    ((d << 1) ^ (d >> 31)) as u32
}

/// A FIFO as the decoder keeps it: index 0 is the most recent push; only
/// the entries pushed so far are readable.
struct Fifo<T: Copy + PartialEq, const N: usize> {
    items: [T; N],
    head: usize,
    filled: usize,
}

impl<T: Copy + PartialEq, const N: usize> Fifo<T, N> {
    fn new(zero: T) -> Self {
        Fifo {
            items: [zero; N],
            head: 0,
            filled: 0,
        }
    }

    fn push(&mut self, v: T) {
        self.items[self.head] = v;
        self.head = (self.head + 1) % N;
        self.filled = (self.filled + 1).min(N);
    }

    /// The position (0: most recent) of `v` among positions `from..limit`.
    fn find(&self, v: T, from: usize, limit: usize) -> Option<usize> {
        (from..self.filled.min(limit)).find(|&k| self.items[(self.head + N - 1 - k) % N] == v)
    }
}

/// One triangle's code, before the table is known.
enum Code {
    /// An edge-FIFO hit: the code byte and extra data.
    Edge(u8, Vec<u8>),
    /// No edge: `a` is `next` and b, c fit nibbles 0..=14 (`0xfY` or
    /// `0xfe` with the byte `zw`).
    Fresh(u8),
    /// No edge, in full: the code (`0xfe` or `0xff`), then the `zw` byte
    /// and the deltas.
    Full(u8, Vec<u8>),
}

/// The decoder's state while encoding triangles.
struct State {
    edges: Fifo<(u32, u32), 16>,
    vertices: Fifo<u32, 16>,
    next: u32,
    last: u32,
}

impl State {
    /// The third index of an edge-coded triangle: its nibble and data.
    fn third(&mut self, c: u32, data: &mut Vec<u8>) -> u8 {
        if c == self.next {
            self.next = self.next.wrapping_add(1);
            self.vertices.push(c);
            return 0;
        }
        if let Some(k) = self.vertices.find(c, 1, 13) {
            return k as u8;
        }
        let code = if c == self.last.wrapping_sub(1) {
            0xd
        } else if c == self.last.wrapping_add(1) {
            0xe
        } else {
            push_varint(data, zigzag_delta(c, self.last));
            0xf
        };
        self.last = c;
        self.vertices.push(c);
        code
    }

    /// The nibble of `b` or `c` of a triangle without an edge: 0 for `next`,
    /// 1..=14 for the vertex FIFO (read before this triangle's pushes),
    /// 15 for a delta.
    fn nibble(&mut self, x: u32, fifo: &Fifo<u32, 16>) -> u8 {
        if x == self.next {
            self.next = self.next.wrapping_add(1);
            0
        } else {
            fifo.find(x, 0, 14).map_or(15, |k| k as u8 + 1)
        }
    }

    /// How many bytes beyond the code byte an edge-coded triangle with
    /// third index `c` takes, roughly (0 for `next`, a FIFO vertex or
    /// `last ± 1`).
    fn third_cost(&self, c: u32) -> usize {
        let near = c == self.next
            || self.vertices.find(c, 1, 13).is_some()
            || c == self.last.wrapping_sub(1)
            || c == self.last.wrapping_add(1);
        if near {
            0
        } else {
            1
        }
    }

    /// The rotation of `t` to code: with `rotate`, the one with an edge in
    /// the FIFO and the cheapest third index, else one starting at `next`.
    fn rotation(&self, t: [u32; 3], rotate: bool) -> [u32; 3] {
        if !rotate {
            return t;
        }
        let turns = [t, [t[1], t[2], t[0]], [t[2], t[0], t[1]]];
        let edge = turns
            .iter()
            .filter_map(|r| {
                let x = self.edges.find((r[0], r[1]), 0, 15)?;
                Some(((self.third_cost(r[2]), x), *r))
            })
            .min_by_key(|(k, _)| *k);
        if let Some((_, r)) = edge {
            return r;
        }
        turns
            .iter()
            .copied()
            .find(|r| r[0] == self.next)
            .unwrap_or(t)
    }

    fn code(&mut self, [a, b, c]: [u32; 3]) -> Code {
        if let Some(x) = self.edges.find((a, b), 0, 15) {
            let mut data = Vec::new();
            let y = self.third(c, &mut data);
            self.edges.push((c, b));
            self.edges.push((a, c));
            return Code::Edge(((x as u8) << 4) | y, data);
        }
        let before = self.vertices.clone_fifo();
        let fresh_a = a == self.next;
        // A `zw` byte of 0 resets `next`: harmless only when it is 0.
        if fresh_a {
            self.next = self.next.wrapping_add(1);
        }
        let z = self.nibble(b, &before);
        let mut w = self.nibble(c, &before);
        if z == 0 && w == 0 && !fresh_a && self.next != 2 {
            // 0xff with zw = 0 would reset next before a: undo and spell c.
            self.next = self.next.wrapping_sub(1);
            w = 15;
        }
        let zw = (z << 4) | w;
        self.edges.push((b, a));
        self.edges.push((c, b));
        self.edges.push((a, c));
        self.vertices.push(a);
        if z == 0 || z == 15 {
            self.vertices.push(b);
        }
        if w == 0 || w == 15 {
            self.vertices.push(c);
        }
        if fresh_a && z != 15 && w != 15 {
            return Code::Fresh(zw);
        }
        let mut data = vec![zw];
        let mut spell = |x: u32, data: &mut Vec<u8>| {
            push_varint(data, zigzag_delta(x, self.last));
            self.last = x;
        };
        if !fresh_a {
            spell(a, &mut data);
        }
        if z == 15 {
            spell(b, &mut data);
        }
        if w == 15 {
            spell(c, &mut data);
        }
        Code::Full(if fresh_a { 0xfe } else { 0xff }, data)
    }
}

impl Fifo<u32, 16> {
    fn clone_fifo(&self) -> Self {
        Fifo {
            items: self.items,
            head: self.head,
            filled: self.filled,
        }
    }
}

/// Encodes a triangle list (`indices.len()` a multiple of 3) as an index
/// buffer stream (`EXT_meshopt_compression` mode `TRIANGLES`); it decodes
/// to `indices` exactly.
///
/// # Errors
/// [`MeshoptError`] when the count is not a multiple of 3.
pub fn encode_triangles(indices: &[u32]) -> Result<Vec<u8>, MeshoptError> {
    encode(indices, false).map(|(bytes, _)| bytes)
}

/// As [`encode_triangles`], each triangle turned (same winding) to the
/// rotation that codes shortest; returns the stream and the triangles it
/// decodes to.
///
/// # Errors
/// As [`encode_triangles`].
pub fn encode_triangles_rotated(indices: &[u32]) -> Result<(Vec<u8>, Vec<u32>), MeshoptError> {
    encode(indices, true)
}

fn encode(indices: &[u32], rotate: bool) -> Result<(Vec<u8>, Vec<u32>), MeshoptError> {
    if !indices.len().is_multiple_of(3) {
        return Err(MeshoptError(format!(
            "triangles: {} indices is not a multiple of 3",
            indices.len()
        )));
    }
    let mut state = State {
        edges: Fifo::new((0, 0)),
        vertices: Fifo::new(0),
        next: 0,
        last: 0,
    };
    let mut order = Vec::with_capacity(indices.len());
    let codes: Vec<Code> = indices
        .chunks_exact(3)
        .map(|t| {
            let r = state.rotation([t[0], t[1], t[2]], rotate);
            order.extend_from_slice(&r);
            state.code(r)
        })
        .collect();
    let table = code_table(&codes);
    let mut out = Vec::with_capacity(1 + codes.len() * 2 + 16);
    out.push(0xe1);
    let mut data = Vec::new();
    for code in &codes {
        match code {
            Code::Edge(byte, extra) => {
                out.push(*byte);
                data.extend_from_slice(extra);
            }
            Code::Fresh(zw) => match table.iter().position(|t| t == zw) {
                Some(y) => out.push(0xf0 | y as u8),
                None => {
                    out.push(0xfe);
                    data.push(*zw);
                }
            },
            Code::Full(byte, extra) => {
                out.push(*byte);
                data.extend_from_slice(extra);
            }
        }
    }
    out.extend_from_slice(&data);
    let mut tail = [0u8; 16];
    tail[..table.len()].copy_from_slice(&table);
    out.extend_from_slice(&tail);
    Ok((out, order))
}

/// The `codeaux` entries: the (up to) 14 most frequent `zw` bytes of the
/// triangles coded from `next` and the vertex FIFO (no nibble is 15), `0x00`
/// always among them when used (spelt as `0xfe 0x00` it would reset `next`).
fn code_table(codes: &[Code]) -> Vec<u8> {
    let mut counts: HashMap<u8, usize> = HashMap::new();
    for code in codes {
        if let Code::Fresh(zw) = code {
            *counts.entry(*zw).or_default() += 1;
        }
    }
    let mut ranked: Vec<(u8, usize)> = counts.into_iter().collect();
    ranked.sort_by(|x, y| (y.0 == 0, y.1).cmp(&(x.0 == 0, x.1)).then(x.0.cmp(&y.0)));
    ranked.into_iter().take(14).map(|(zw, _)| zw).collect()
}

/// Encodes a list of indices as an index sequence stream
/// (`EXT_meshopt_compression` mode `INDICES`).
///
/// # Errors
/// [`MeshoptError`] when a difference from both baselines is outside
/// [−2³⁰, 2³⁰) (the format's limit).
pub fn encode_index_sequence(indices: &[u32]) -> Result<Vec<u8>, MeshoptError> {
    let mut out = Vec::with_capacity(1 + indices.len() + 4);
    out.push(0xd1);
    let mut last = [0u32; 2];
    for (k, &x) in indices.iter().enumerate() {
        let deltas = last.map(|l| i64::from(x.wrapping_sub(l) as i32));
        let pick = usize::from(deltas[1].abs() < deltas[0].abs());
        let d = deltas[pick];
        if !(-(1 << 30)..(1 << 30)).contains(&d) {
            return Err(MeshoptError(format!(
                "index sequence: index {k} ({x}) is more than 2^30 from both baselines"
            )));
        }
        let zz = ((d << 1) ^ (d >> 63)) as u32;
        push_varint(&mut out, (zz << 1) | pick as u32);
        last[pick] = x;
    }
    out.extend_from_slice(&[0; 4]);
    Ok(out)
}
