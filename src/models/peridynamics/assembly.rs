//! The stiffness of a free node's equation, gathered as 2x2 blocks by column node and
//! condensed onto the free unknowns: a collar column moves to the right-hand side with
//! its prescribed displacement, a fictitious node's column is spread over the free
//! nodes of its extension ([`super::extension`]) and its traction part moves to the
//! right-hand side,
//!
//! ```text
//! K_kl u_l  ->  K_kl (sum_i E_li u_i + F_l t)   (l fictitious),     rhs_k -= K_kl u_l   (l in the collar).
//! ```
//!
//! Used for the bonds and the dilatation together whenever a run has the dilatation
//! term or fictitious nodes; the plain bond-based stiffness keeps its direct assembly
//! ([`super::operator::Bonds::stiffness_rows`]), which this reproduces.

use super::extension::Extension;
use super::nodes::PdNodes;
use crate::linalg::Csr;

/// The rows of one free node: columns (dofs), x-row and y-row values, right-hand side.
pub type NodeRows = (Vec<u32>, Vec<f64>, Vec<f64>, [f64; 2]);

/// One free node's row being gathered (per thread; zero between rows).
pub struct RowBuilder<'a> {
    nodes: &'a PdNodes,
    /// The extension and the traction parts of the fictitious nodes, when condensing.
    condense: Option<(Option<&'a Extension>, &'a [[f64; 2]])>,
    acc: Vec<[f64; 4]>,
    seen: Vec<bool>,
    touched: Vec<u32>,
    rhs: [f64; 2],
}

/// `B u` for a block `[xx, xy, yx, yy]`.
fn times(b: [f64; 4], u: [f64; 2]) -> [f64; 2] {
    [b[0] * u[0] + b[1] * u[1], b[2] * u[0] + b[3] * u[1]]
}

/// The block product `A B`.
fn product(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [a[0] * b[0] + a[1] * b[2], a[0] * b[1] + a[1] * b[3], a[2] * b[0] + a[3] * b[2], a[2] * b[1] + a[3] * b[3]]
}

impl<'a> RowBuilder<'a> {
    /// A builder condensing onto the free unknowns (`extension` for the fictitious
    /// nodes with their traction parts), or keeping every node's column (`None`).
    pub fn new(nodes: &'a PdNodes, condense: Option<(Option<&'a Extension>, &'a [[f64; 2]])>) -> Self {
        let n = if condense.is_some() { nodes.free } else { nodes.len() };
        RowBuilder { nodes, condense, acc: vec![[0.0; 4]; n], seen: vec![false; n], touched: Vec::new(), rhs: [0.0; 2] }
    }

    fn gather(&mut self, l: usize, b: [f64; 4]) {
        if !self.seen[l] {
            self.seen[l] = true;
            self.touched.push(l as u32);
        }
        let e = &mut self.acc[l];
        for (e, b) in e.iter_mut().zip(b) {
            *e += b;
        }
    }

    /// Add the block `b` in the column of node `l` (module docs).
    pub fn add(&mut self, l: usize, b: [f64; 4]) {
        let nodes = self.nodes;
        match self.condense {
            Some(_) if l < nodes.free => self.gather(l, b),
            None => self.gather(l, b),
            Some((_, _)) if l < nodes.fictitious => {
                let r = times(b, nodes.prescribed[l - nodes.free]);
                self.rhs = [self.rhs[0] - r[0], self.rhs[1] - r[1]];
            }
            Some((extension, parts)) => {
                let g = l - nodes.fictitious;
                let extension = extension.expect("fictitious nodes come with their extension");
                let r = times(b, parts[g]);
                self.rhs = [self.rhs[0] - r[0], self.rhs[1] - r[1]];
                for &(i, e) in extension.terms(g) {
                    self.gather(i as usize, product(b, e));
                }
            }
        }
    }

    /// Add `r` to the right-hand side.
    pub fn load(&mut self, r: [f64; 2]) {
        self.rhs = [self.rhs[0] + r[0], self.rhs[1] + r[1]];
    }

    /// The gathered blocks by column node in increasing order and the right-hand side;
    /// the builder is empty again.
    pub fn take(&mut self) -> (Vec<(u32, [f64; 4])>, [f64; 2]) {
        self.touched.sort_unstable();
        let blocks = self
            .touched
            .iter()
            .map(|&l| {
                self.seen[l as usize] = false;
                (l, std::mem::take(&mut self.acc[l as usize]))
            })
            .collect();
        self.touched.clear();
        (blocks, std::mem::take(&mut self.rhs))
    }

    /// The node's two rows over the free unknowns (interleaved dofs `2 l`, `2 l + 1`).
    pub fn finish(&mut self) -> NodeRows {
        let (blocks, rhs) = self.take();
        let dofs = self.nodes.dofs();
        let (mut cols, mut top, mut bottom) = (Vec::with_capacity(2 * blocks.len()), Vec::new(), Vec::new());
        for (l, e) in blocks {
            cols.extend([dofs.dof(l as usize, 0) as u32, dofs.dof(l as usize, 1) as u32]);
            top.extend([e[0], e[1]]);
            bottom.extend([e[2], e[3]]);
        }
        (cols, top, bottom, rhs)
    }
}

/// The compressed rows and right-hand side of every free node's rows, in order.
pub fn compressed(rows: Vec<NodeRows>) -> (Csr, Vec<f64>) {
    let n = 2 * rows.len();
    let nnz: usize = rows.iter().map(|r| 2 * r.0.len()).sum();
    let (mut offsets, mut cols, mut values, mut rhs) =
        (Vec::with_capacity(n + 1), Vec::with_capacity(nnz), Vec::with_capacity(nnz), Vec::with_capacity(n));
    offsets.push(0);
    for (c, top, bottom, r) in rows {
        for vals in [top, bottom] {
            cols.extend_from_slice(&c);
            values.extend(vals);
            offsets.push(cols.len());
        }
        rhs.extend(r);
    }
    (Csr::from_parts(n, n, offsets, cols, values), rhs)
}

/// `0..n` in about four ranges per thread, for one [`RowBuilder`] each.
pub fn chunks(n: usize) -> Vec<std::ops::Range<usize>> {
    let count = (4 * rayon::current_num_threads()).max(1);
    let size = n.div_ceil(count).max(1);
    (0..n).step_by(size).map(|a| a..(a + size).min(n)).collect()
}
