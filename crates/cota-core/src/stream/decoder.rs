//! The receiving end of both stream kinds: one decoder that applies steps
//! one by one and yields the mesh and the surface of the prefix (paper
//! `000_ebf7e3a88dffd361.txt` §3). A step that fails to decode is rolled
//! back, so the decoder always holds the last good prefix.

use super::format::{height_of, StreamError, StreamHeader, StreamKind, UNKNOWN};
use super::models::Models;
use super::state::State;
use super::{marks, steps};
use crate::mesh::Mesh;

/// Statistics of one applied step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepInfo {
    /// Index of the step (0 = the coarse mesh).
    pub index: usize,
    /// The stated max error of the prefix ending here, metres.
    pub max_error_m: f64,
    /// Points whose height this step carried.
    pub new_points: usize,
    /// Bytes of the step's payload.
    pub payload_bytes: usize,
    /// Triangles of the prefix's mesh.
    pub triangles: usize,
    /// Vertices of the prefix's mesh.
    pub vertices: usize,
}

/// The receiving end: applies steps and yields the mesh of the prefix.
#[derive(Debug, Clone)]
pub struct StreamDecoder {
    header: StreamHeader,
    state: State,
    models: Models,
    steps: Vec<StepInfo>,
    /// Marks streams: the mesh `refine::triangulate` makes of the marks.
    marks_mesh: Option<Mesh>,
}

impl StreamDecoder {
    /// A decoder for a stream with this header.
    pub fn new(header: StreamHeader) -> Self {
        let state = State::new(&header);
        StreamDecoder {
            header,
            state,
            models: Models::new(),
            steps: Vec::new(),
            marks_mesh: None,
        }
    }

    /// The header.
    pub fn header(&self) -> &StreamHeader {
        &self.header
    }

    /// The steps applied so far.
    pub fn steps(&self) -> &[StepInfo] {
        &self.steps
    }

    /// The stated max error of the current prefix (`None` before step 0).
    pub fn max_error_m(&self) -> Option<f64> {
        self.steps.last().map(|s| s.max_error_m)
    }

    /// Applies one step payload. On error the decoder keeps the previous prefix.
    ///
    /// # Errors
    /// [`StreamError::BadStep`] when the payload is short, states an error that
    /// is negative, NaN, above `f32::MAX` or (error-steps streams) above the
    /// previous step's, or its coded block is truncated or corrupted (for
    /// marks streams also: its points disagree with their closure).
    pub fn apply_step(&mut self, payload: &[u8]) -> Result<StepInfo, StreamError> {
        let index = self.steps.len();
        let bad = |expected: String, found: String| StreamError::BadStep {
            step: index,
            expected,
            found,
        };
        let [e0, e1, e2, e3, ..] = *payload else {
            return Err(bad(
                "at least 4 bytes".into(),
                format!("{} bytes", payload.len()),
            ));
        };
        let stated = f32::from_le_bytes([e0, e1, e2, e3]) as f64;
        // Marks streams state exact measured errors, which need not decrease.
        let prev = match self.header.kind {
            StreamKind::ErrorSteps => self.max_error_m().unwrap_or(f64::INFINITY),
            StreamKind::Marks(_) => f32::MAX as f64,
        };
        if !(stated >= 0.0 && stated <= prev) {
            return Err(bad(
                format!("a stated max error between 0 m and {prev} m"),
                format!("{stated} m"),
            ));
        }
        let block = &payload[4..];
        let saved = self.models.clone();
        let decoded = match self.header.kind {
            StreamKind::ErrorSteps => {
                steps::decode_step(&mut self.state, &mut self.models, index, block).map(|n| {
                    let (triangles, vertices) = self.state.counts();
                    (n, triangles, vertices, None)
                })
            }
            StreamKind::Marks(mode) => marks::decode_step(
                &mut self.state,
                &mut self.models,
                &self.header,
                mode,
                index,
                block,
            )
            .map(|(mesh, n)| (n, mesh.triangle_count(), mesh.vertex_count(), Some(mesh)))
            .map_err(|found| bad("a decodable marks step".into(), found)),
        };
        let (new_points, triangles, vertices, mesh) = match decoded {
            Ok(d) => d,
            Err(e) => {
                self.models = saved;
                return Err(e);
            }
        };
        if mesh.is_some() {
            self.marks_mesh = mesh;
        }
        let info = StepInfo {
            index,
            max_error_m: stated,
            new_points,
            payload_bytes: payload.len(),
            triangles,
            vertices,
        };
        self.steps.push(info);
        Ok(info)
    }

    /// The mesh of the current prefix (empty before step 0), vertex heights
    /// `q · quantum_m` as `f32`: equal, vertex for vertex, to
    /// `Bitree::extract(E_k)` on the quantised grid (marks streams: to the
    /// sender's `refine::triangulate` of step `k`'s marks).
    pub fn mesh(&self) -> Mesh {
        if self.steps.is_empty() {
            return Mesh::default();
        }
        if let Some(m) = &self.marks_mesh {
            return m.clone();
        }
        let mut m = self.state.mesh();
        let w = self.header.width as usize;
        for v in &mut m.vertices {
            let q = self.state.q[v.row as usize * w + v.col as usize];
            v.z_m = height_of(q, self.header.quantum_m);
        }
        m
    }

    /// The height of every sample as the current prefix's surface gives it:
    /// sent heights exactly, the others interpolated on their leaf (midpoint
    /// of each hypotenuse, recursively, which is the leaf's plane). When the
    /// stated max error is below `quantum_m / 2`, interpolated heights are
    /// rounded to the lattice, which recovers them exactly. `None` before step 0.
    pub fn heights_m(&self) -> Option<Vec<f32>> {
        let stated = self.max_error_m()?;
        let qm = self.header.quantum_m;
        let snap = stated < qm / 2.0;
        let hier = self.state.hier;
        let mut z: Vec<f64> = self
            .state
            .q
            .iter()
            .map(|&q| {
                if q == UNKNOWN {
                    f64::NAN
                } else {
                    q as f64 * qm
                }
            })
            .collect();
        if let Some(m) = &self.marks_mesh {
            // Fictitious vertices carry their interpolated mesh height.
            let w = hier.width() as usize;
            for v in &m.vertices {
                z[v.row as usize * w + v.col as usize] = v.z_m as f64;
            }
        }
        self.state.leaves(|leaf| {
            let mut stack = vec![*leaf];
            while let Some(t) = stack.pop() {
                if t.is_unit() {
                    continue;
                }
                let i = hier.index(t.mid());
                if z[i].is_nan() {
                    let v = (z[hier.index(t.a)] + z[hier.index(t.b)]) / 2.0;
                    z[i] = if snap { (v / qm).round() * qm } else { v };
                }
                let (c0, c1) = t.children();
                stack.push(c0);
                stack.push(c1);
            }
        });
        Some(z.into_iter().map(|v| v as f32).collect())
    }
}
