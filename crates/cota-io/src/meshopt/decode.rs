//! Decoders of the three `EXT_meshopt_compression` bitstreams (Appendix A of
//! its specification), for the pyramid's check and the tests: written from
//! the specification's decoding steps, sharing no code with the encoders
//! ([`super::vertex`], [`super::index`]), every read bounds-checked.

use super::MeshoptError;

fn err(what: impl Into<String>) -> MeshoptError {
    MeshoptError(what.into())
}

/// A cursor over a byte slice; reading past its end is an error.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn byte(&mut self) -> Result<u8, MeshoptError> {
        let b = *self
            .bytes
            .get(self.at)
            .ok_or_else(|| err(format!("truncated at byte {}", self.at)))?;
        self.at += 1;
        Ok(b)
    }

    fn take(&mut self, n: usize) -> Result<&[u8], MeshoptError> {
        let s = self
            .bytes
            .get(self.at..self.at.saturating_add(n))
            .ok_or_else(|| err(format!("truncated at byte {}", self.at)))?;
        self.at += n;
        Ok(s)
    }

    /// An unsigned LEB128 of at most 32 bits.
    fn varint(&mut self) -> Result<u32, MeshoptError> {
        let mut v = 0u32;
        for shift in (0..35).step_by(7) {
            let b = self.byte()?;
            v |= u32::from(b & 0x7f).checked_shl(shift).unwrap_or(0);
            if b < 0x80 {
                return Ok(v);
            }
        }
        Err(err("varint longer than 5 bytes"))
    }
}

fn unzigzag32(v: u32) -> u32 {
    (v >> 1) ^ 0u32.wrapping_sub(v & 1)
}

/// Decodes `count` elements of `stride` bytes from a vertex buffer stream.
///
/// # Errors
/// [`MeshoptError`] on a bad header or stride, truncated data, or data
/// left between the last block and the tail.
pub fn decode_vertex_buffer(
    src: &[u8],
    count: usize,
    stride: usize,
) -> Result<Vec<u8>, MeshoptError> {
    if stride == 0 || !stride.is_multiple_of(4) || stride > 256 {
        return Err(err(format!("bad vertex stride {stride}")));
    }
    if src.first() != Some(&0xa0) {
        return Err(err("vertex stream: expected the header 0xa0"));
    }
    if count > src.len().saturating_mul(256) {
        return Err(err(format!("{count} elements from {} bytes", src.len())));
    }
    let tail = stride.max(32);
    let end = src
        .len()
        .checked_sub(tail)
        .filter(|&e| e >= 1)
        .ok_or_else(|| err("vertex stream shorter than its tail"))?;
    let mut base: Vec<u8> = src[src.len() - stride..].to_vec();
    let mut r = Reader {
        bytes: &src[..end],
        at: 1,
    };
    let block = ((8192 / stride) & !15).min(256);
    let mut out = vec![
        0u8;
        count
            .checked_mul(stride)
            .ok_or_else(|| err("too many elements"))?
    ];
    let mut first = 0;
    while first < count {
        let n = block.min(count - first);
        let groups = n.div_ceil(16);
        for k in 0..stride {
            let header = r.take(groups.div_ceil(4))?.to_vec();
            let mut deltas = Vec::with_capacity(groups * 16);
            for g in 0..groups {
                let mode = (header[g / 4] >> (2 * (g % 4))) & 3;
                let bits: usize = [0, 2, 4, 8][mode as usize];
                deltas.extend(group(&mut r, bits)?);
            }
            for (i, &d) in deltas.iter().take(n).enumerate() {
                let delta = if d & 1 != 0 { !(d >> 1) } else { d >> 1 };
                base[k] = base[k].wrapping_add(delta);
                out[(first + i) * stride + k] = base[k];
            }
        }
        first += n;
    }
    if r.at != end {
        return Err(err(format!(
            "vertex stream: {} bytes before the tail unread",
            end - r.at
        )));
    }
    Ok(out)
}

/// One group of 16 byte codes with `bits` per value (0, 2, 4 or 8).
fn group(r: &mut Reader<'_>, bits: usize) -> Result<[u8; 16], MeshoptError> {
    let mut g = [0u8; 16];
    match bits {
        0 => {}
        8 => g.copy_from_slice(r.take(16)?),
        _ => {
            let packed = r.take(2 * bits)?.to_vec();
            let per = 8 / bits;
            let sentinel = (1u8 << bits) - 1;
            for (m, v) in g.iter_mut().enumerate() {
                let shift = 8 - bits * (m % per + 1);
                let x = (packed[m / per] >> shift) & sentinel;
                *v = if x == sentinel { r.byte()? } else { x };
            }
        }
    }
    Ok(g)
}

/// The triangle decoder's state: `next`, `last`, the FIFOs (most recent
/// last; only what was pushed is readable).
#[derive(Default)]
struct Triangles {
    edges: Vec<(u32, u32)>,
    verts: Vec<u32>,
    next: u32,
    last: u32,
}

impl Triangles {
    fn edge(&self, k: usize) -> Result<(u32, u32), MeshoptError> {
        self.edges
            .len()
            .checked_sub(k + 1)
            .map(|i| self.edges[i])
            .ok_or_else(|| err("edge FIFO read before written"))
    }

    fn vert(fifo: &[u32], k: usize) -> Result<u32, MeshoptError> {
        fifo.len()
            .checked_sub(k + 1)
            .map(|i| fifo[i])
            .ok_or_else(|| err("vertex FIFO read before written"))
    }

    fn fresh(&mut self) -> u32 {
        self.next = self.next.wrapping_add(1);
        self.next.wrapping_sub(1)
    }

    fn delta(&mut self, data: &mut Reader<'_>) -> Result<u32, MeshoptError> {
        self.last = self.last.wrapping_add(unzigzag32(data.varint()?));
        Ok(self.last)
    }

    /// Code `0xXY`, X < 15: an edge from the FIFO and a third index.
    fn with_edge(
        &mut self,
        x: usize,
        y: u8,
        data: &mut Reader<'_>,
    ) -> Result<[u32; 3], MeshoptError> {
        let (a, b) = self.edge(x)?;
        let c = match y {
            0 => self.fresh(),
            1..=12 => Self::vert(&self.verts, y as usize)?,
            13 => {
                self.last = self.last.wrapping_sub(1);
                self.last
            }
            14 => {
                self.last = self.last.wrapping_add(1);
                self.last
            }
            _ => self.delta(data)?,
        };
        if y == 0 || y >= 13 {
            self.verts.push(c);
        }
        self.edges.extend([(c, b), (a, c)]);
        Ok([a, b, c])
    }

    /// Code `0xfY`: three indices, from the table (Y < 14) or spelt.
    fn without_edge(
        &mut self,
        y: u8,
        table: &[u8],
        data: &mut Reader<'_>,
    ) -> Result<[u32; 3], MeshoptError> {
        let zw = if y < 14 {
            table[y as usize]
        } else {
            data.byte()?
        };
        if y >= 14 && zw == 0 {
            self.next = 0;
        }
        let before = self.verts.clone();
        let a = if y == 15 {
            self.delta(data)?
        } else {
            self.fresh()
        };
        let mut pick = |n: u8| -> Result<u32, MeshoptError> {
            match n {
                0 => Ok(self.fresh()),
                15 if y >= 14 => self.delta(data),
                15 => Err(err("table entry with a nibble 15")),
                _ => Self::vert(&before, n as usize - 1),
            }
        };
        let (z, w) = (zw >> 4, zw & 15);
        let b = pick(z)?;
        let c = pick(w)?;
        self.verts.push(a);
        if z == 0 || z == 15 {
            self.verts.push(b);
        }
        if w == 0 || w == 15 {
            self.verts.push(c);
        }
        self.edges.extend([(b, a), (c, b), (a, c)]);
        Ok([a, b, c])
    }
}

/// Decodes `count` indices (a multiple of 3) from a triangle stream.
///
/// # Errors
/// [`MeshoptError`] on a bad header or count, truncated data, a read of a
/// FIFO entry never written, or data left before the table.
pub fn decode_triangles(src: &[u8], count: usize) -> Result<Vec<u32>, MeshoptError> {
    if !count.is_multiple_of(3) {
        return Err(err(format!("{count} triangle indices")));
    }
    let tris = count / 3;
    if src.first() != Some(&0xe1) || src.len() < 1 + tris + 16 {
        return Err(err(
            "triangle stream: expected 0xe1, a code per triangle and a 16-byte table",
        ));
    }
    let table = &src[src.len() - 16..];
    let mut data = Reader {
        bytes: &src[1 + tris..src.len() - 16],
        at: 0,
    };
    let mut state = Triangles::default();
    let mut out = Vec::with_capacity(count);
    for &code in &src[1..1 + tris] {
        let (hi, lo) = ((code >> 4) as usize, code & 15);
        let tri = if hi < 15 {
            state.with_edge(hi, lo, &mut data)?
        } else {
            state.without_edge(lo, table, &mut data)?
        };
        if state.edges.len() > 64 {
            state.edges.drain(..state.edges.len() - 16);
        }
        if state.verts.len() > 64 {
            state.verts.drain(..state.verts.len() - 16);
        }
        out.extend_from_slice(&tri);
    }
    if data.at != data.bytes.len() {
        return Err(err("triangle stream: extra data before the table"));
    }
    Ok(out)
}

/// Decodes `count` indices from an index sequence stream.
///
/// # Errors
/// [`MeshoptError`] on a bad header, truncated data, or a tail that is not 4
/// bytes after the last index.
pub fn decode_index_sequence(src: &[u8], count: usize) -> Result<Vec<u32>, MeshoptError> {
    if src.first() != Some(&0xd1) || src.len() < 5 {
        return Err(err("index sequence: expected 0xd1 and a 4-byte tail"));
    }
    let mut r = Reader {
        bytes: &src[..src.len() - 4],
        at: 1,
    };
    let mut last = [0u32; 2];
    let mut out = Vec::with_capacity(count.min(src.len()));
    for _ in 0..count {
        let v = r.varint()?;
        let k = (v & 1) as usize;
        last[k] = last[k].wrapping_add(unzigzag32(v >> 1));
        out.push(last[k]);
    }
    if r.at != r.bytes.len() {
        return Err(err("index sequence: extra data before the tail"));
    }
    Ok(out)
}
