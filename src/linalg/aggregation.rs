//! The coarse spaces of smoothed aggregation ([`super::amg`]): the strength graph
//! between nodes, aggregates of nodes, and the tentative prolongator that carries the
//! near-null space (rigid-body modes) exactly onto each aggregate.
//!
//! Vaněk, Mandel, Brezina, "Algebraic multigrid by smoothed aggregation for second and
//! fourth order elliptic problems", *Computing* 56 (1996) 179–196, §3; the three
//! aggregation passes follow their Algorithm 1 (as in pyamg's `standard_aggregation`).

use super::csr::Csr;
use nalgebra::DMatrix;
use rayon::prelude::*;

/// Unknowns of a level grouped by node: `block` consecutive unknowns per node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Blocks {
    /// Unknowns per node (2 on the finest Navier level, the number of near-null
    /// vectors on coarse levels).
    pub block: usize,
    /// Nodes (`unknowns / block`).
    pub nodes: usize,
}

/// A graph over the nodes of a level in compressed form: the neighbours of node `i`
/// are `neighbours[offsets[i]..offsets[i + 1]]`, sorted, without `i` itself. (One
/// flat array: the million small per-node lists it replaces were slow to build and
/// stayed resident in the allocator's arenas after they were freed;
/// docs/notebook/round2-target-error.md, "One copy of the matrix in the solve".)
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NodeGraph {
    offsets: Vec<usize>,
    neighbours: Vec<u32>,
}

impl NodeGraph {
    /// The graph with the given sorted adjacency lists.
    pub fn from_lists(lists: &[Vec<u32>]) -> Self {
        let mut offsets = vec![0];
        let mut neighbours = Vec::new();
        for list in lists {
            neighbours.extend_from_slice(list);
            offsets.push(neighbours.len());
        }
        NodeGraph { offsets, neighbours }
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Whether the graph has no node.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Neighbours of node `i`, sorted.
    pub fn of(&self, i: usize) -> &[u32] {
        &self.neighbours[self.offsets[i]..self.offsets[i + 1]]
    }
}

/// Nodes handed to one task of [`strength_graph`].
const NODES_PER_TASK: usize = 4096;

/// The node graph of `a`: `J` is a neighbour of `I` when some entry couples an unknown
/// of `I` with one of `J` and its block is strong,
/// `‖A_IJ‖_F ≥ θ √(‖A_II‖_F ‖A_JJ‖_F)` (Vaněk et al. eq. 3.1 with block norms), in
/// either direction: collocation stencils are not symmetric (`j` in the support of `i`
/// does not put `i` in that of `j`), and aggregates are built on the symmetrised graph.
///
/// Nodes in parallel: the strong couplings out of each node (block norms summed in a
/// dense row with a marker per node), then their union with the transpose, merged node
/// by node.
pub fn strength_graph(a: &Csr, blocks: Blocks, theta: f64) -> NodeGraph {
    let (b, nodes) = (blocks.block, blocks.nodes);
    let (ptr, idx, val) = (a.row_offsets(), a.col_indices(), a.values());
    let entries_of =
        |node: usize| (node * b..(node + 1) * b).flat_map(|row| ptr[row]..ptr[row + 1]).map(|k| (idx[k] as usize / b, val[k] * val[k]));
    // ‖A_II‖² of every node.
    let diag: Vec<f64> = (0..nodes).into_par_iter().map(|node| entries_of(node).filter(|e| e.0 == node).map(|e| e.1).sum()).collect();
    let tasks = nodes.div_ceil(NODES_PER_TASK);
    let parts: Vec<(Vec<usize>, Vec<u32>)> = (0..tasks)
        .into_par_iter()
        .map_init(
            || (vec![usize::MAX; nodes], vec![0.0f64; nodes], Vec::<u32>::new()),
            |(mark, norm, touched), task| {
                let (mut lengths, mut strong) = (Vec::new(), Vec::new());
                for node in task * NODES_PER_TASK..nodes.min((task + 1) * NODES_PER_TASK) {
                    touched.clear();
                    for (other, n2) in entries_of(node).filter(|e| e.0 != node) {
                        if mark[other] != node {
                            mark[other] = node;
                            norm[other] = 0.0;
                            touched.push(other as u32);
                        }
                        norm[other] += n2;
                    }
                    touched.sort_unstable();
                    let before = strong.len();
                    // ‖A_IJ‖ ≥ θ √(‖A_II‖ ‖A_JJ‖)  ⇔  ‖A_IJ‖⁴ ≥ θ⁴ ‖A_II‖² ‖A_JJ‖².
                    strong.extend(touched.iter().copied().filter(|&o| {
                        let n2 = norm[o as usize];
                        theta == 0.0 || n2 * n2 >= theta.powi(4) * diag[node] * diag[o as usize]
                    }));
                    lengths.push(strong.len() - before);
                }
                (lengths, strong)
            },
        )
        .collect();
    let mut out_offsets = Vec::with_capacity(nodes + 1);
    out_offsets.push(0usize);
    for len in parts.iter().flat_map(|p| &p.0) {
        out_offsets.push(out_offsets[out_offsets.len() - 1] + len);
    }
    let out: Vec<u32> = parts.into_iter().flat_map(|p| p.1).collect();
    symmetrised(nodes, &out_offsets, &out)
}

/// The graph whose neighbours of each node are the union of its strong couplings out
/// (`out[out_offsets[i]..out_offsets[i + 1]]`, sorted) and into it (by a counting
/// sort, sources in increasing order), merged node by node.
fn symmetrised(nodes: usize, out_offsets: &[usize], out: &[u32]) -> NodeGraph {
    let mut into = vec![0u32; out.len()];
    let in_offsets = super::csr::transposed(nodes, out_offsets, out, |node, _, slot| into[slot] = node as u32);
    let mut offsets = Vec::with_capacity(nodes + 1);
    offsets.push(0usize);
    let mut neighbours = Vec::with_capacity(out.len() + into.len());
    for node in 0..nodes {
        let from = &out[out_offsets[node]..out_offsets[node + 1]];
        let to = &into[in_offsets[node]..in_offsets[node + 1]];
        union_of_sorted(from, to, &mut neighbours);
        offsets.push(neighbours.len());
    }
    neighbours.shrink_to_fit();
    NodeGraph { offsets, neighbours }
}

/// Appends the union of the sorted lists `a` and `b` to `out` (each value once when in
/// both), in increasing order.
fn union_of_sorted(a: &[u32], b: &[u32], out: &mut Vec<u32>) {
    let (mut x, mut y) = (a.iter().peekable(), b.iter().peekable());
    loop {
        let take = match (x.peek(), y.peek()) {
            (Some(&&p), Some(&&q)) => {
                if p <= q {
                    x.next();
                    if p == q {
                        y.next();
                    }
                    p
                } else {
                    y.next();
                    q
                }
            }
            (Some(&&p), None) => {
                x.next();
                p
            }
            (None, Some(&&q)) => {
                y.next();
                q
            }
            (None, None) => break,
        };
        out.push(take);
    }
}

/// Aggregate of every node (`0..count`), from the node graph:
/// 1. a node whose neighbours are all free starts an aggregate with them;
/// 2. a free node joins the aggregate of its first aggregated neighbour;
/// 3. what is left (nodes whose neighbours were taken in pass 2) forms aggregates with
///    its free neighbours.
///
/// Every node ends in an aggregate; an isolated node is an aggregate of its own.
pub fn aggregate(graph: &NodeGraph) -> (Vec<u32>, usize) {
    const FREE: u32 = u32::MAX;
    let n = graph.len();
    let mut agg = vec![FREE; n];
    let mut count = 0u32;
    for i in 0..n {
        if agg[i] != FREE || graph.of(i).iter().any(|&j| agg[j as usize] != FREE) {
            continue;
        }
        agg[i] = count;
        for &j in graph.of(i) {
            agg[j as usize] = count;
        }
        count += 1;
    }
    let first_pass = agg.clone();
    for (i, a) in agg.iter_mut().enumerate() {
        if *a == FREE {
            if let Some(&j) = graph.of(i).iter().find(|&&j| first_pass[j as usize] != FREE) {
                *a = first_pass[j as usize];
            }
        }
    }
    for i in 0..n {
        if agg[i] != FREE {
            continue;
        }
        agg[i] = count;
        for &j in graph.of(i) {
            if agg[j as usize] == FREE {
                agg[j as usize] = count;
            }
        }
        count += 1;
    }
    (agg, count as usize)
}

/// Relative size below which a near-null vector, orthogonalised against the previous
/// ones on an aggregate, counts as dependent (a one-node aggregate cannot carry a
/// rotation besides two translations).
const DEPENDENT: f64 = 1e-10;

/// The tentative prolongator `T` (unknowns × `k · aggregates`) and the coarse near-null
/// space: on each aggregate the rows of the near-null space `null` (unknowns × `k`,
/// row-major) are factored `B_agg = Q R` by modified Gram–Schmidt, `Q` goes into `T`
/// and `R` (`k × k`) into the coarse near-null space, so that `T B_c = B` exactly
/// (Vaněk et al. §3, "tentative prolongator"). Dependent columns are left zero in
/// both; the coarse unknowns they leave without rows are handled by the smoother and
/// the coarsest solve.
pub fn tentative(null: &[f64], k: usize, blocks: Blocks, agg: &[u32], count: usize) -> (Csr, Vec<f64>) {
    let b = blocks.block;
    let n = blocks.nodes * b;
    // The nodes of each aggregate, by a counting sort (flat arrays: no small list per
    // aggregate or unknown).
    let mut start = vec![0usize; count + 1];
    for &a in agg {
        start[a as usize + 1] += 1;
    }
    for a in 0..count {
        start[a + 1] += start[a];
    }
    let mut next = start[..count].to_vec();
    let mut members = vec![0usize; agg.len()];
    for (node, &a) in agg.iter().enumerate() {
        members[next[a as usize]] = node;
        next[a as usize] += 1;
    }
    drop(next);
    // Q by fine unknown: `k` values each (zero in dependent columns).
    let mut q_of = vec![0.0; n * k];
    let mut coarse = vec![0.0; count * k * k];
    for a in 0..count {
        let unknowns: Vec<usize> = members[start[a]..start[a + 1]].iter().flat_map(|&n| n * b..(n + 1) * b).collect();
        let mut q = DMatrix::from_fn(unknowns.len(), k, |r, c| null[unknowns[r] * k + c]);
        let mut r = DMatrix::<f64>::zeros(k, k);
        for c in 0..k {
            let original = q.column(c).norm();
            for p in 0..c {
                let d = q.column(p).dot(&q.column(c));
                r[(p, c)] = d;
                let qp = q.column(p).clone_owned();
                q.column_mut(c).axpy(-d, &qp, 1.0);
            }
            let norm = q.column(c).norm();
            if norm > DEPENDENT * original && norm > 0.0 {
                r[(c, c)] = norm;
                q.column_mut(c).scale_mut(1.0 / norm);
            } else {
                q.column_mut(c).fill(0.0);
            }
        }
        for (local, &u) in unknowns.iter().enumerate() {
            for c in 0..k {
                q_of[u * k + c] = q[(local, c)];
            }
        }
        for i in 0..k {
            for j in 0..k {
                coarse[(a * k + i) * k + j] = r[(i, j)];
            }
        }
    }
    // T: the nonzero entries of each unknown's row, in the columns of its aggregate.
    let nnz = q_of.iter().filter(|&&v| v != 0.0).count();
    let mut offsets = Vec::with_capacity(n + 1);
    offsets.push(0);
    let (mut cols, mut vals) = (Vec::with_capacity(nnz), Vec::with_capacity(nnz));
    for u in 0..n {
        let a = agg[u / b] as usize;
        for c in 0..k {
            let v = q_of[u * k + c];
            if v != 0.0 {
                cols.push((a * k + c) as u32);
                vals.push(v);
            }
        }
        offsets.push(cols.len());
    }
    // Columns are sorted within each row by construction.
    let t = Csr::from_parts(n, count * k, offsets, cols, vals);
    (t, coarse)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1D chain of `n` nodes (tridiagonal blocks).
    fn chain(n: usize) -> NodeGraph {
        let lists: Vec<Vec<u32>> =
            (0..n).map(|i| [i.wrapping_sub(1), i + 1].into_iter().filter(|&j| j < n).map(|j| j as u32).collect()).collect();
        NodeGraph::from_lists(&lists)
    }

    /// Against the definition, written out with ordered maps: a nonsymmetric matrix
    /// of 2x2 blocks over 9000 nodes (three tasks), pseudo-random couplings, at θ = 0
    /// (every coupling) and θ = 0.3 (some dropped in one direction only, so the union
    /// with the transpose matters).
    #[test]
    fn strength_graph_is_the_symmetrised_strong_coupling() {
        let nodes = 9000;
        let mut state = 17u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 33) as usize
        };
        let mut coo = nalgebra_sparse::CooMatrix::new(2 * nodes, 2 * nodes);
        for row in 0..2 * nodes {
            coo.push(row, row, 4.0);
            for _ in 0..5 {
                let col = (row / 2 + next() % 40).min(nodes - 1) * 2 + next() % 2;
                coo.push(row, col, (next() % 1000) as f64 / 500.0 - 1.0);
            }
        }
        let (offsets, cols, vals) = nalgebra_sparse::CsrMatrix::from(&coo).disassemble();
        let a = Csr::from_parts(2 * nodes, 2 * nodes, offsets, cols.into_iter().map(|c| c as u32).collect(), vals);
        let blocks = Blocks { block: 2, nodes };
        for theta in [0.0, 0.3] {
            let mut norm = std::collections::BTreeMap::<(usize, usize), f64>::new();
            for i in 0..a.nrows() {
                for (&j, &v) in a.row(i).col_indices().iter().zip(a.row(i).values()) {
                    *norm.entry((i / 2, j as usize / 2)).or_default() += v * v;
                }
            }
            let diag = |i: usize| norm.get(&(i, i)).copied().unwrap_or(0.0);
            let mut lists = vec![std::collections::BTreeSet::new(); nodes];
            for (&(i, j), &n2) in &norm {
                if i != j && n2.sqrt() >= theta * (diag(i).sqrt() * diag(j).sqrt()).sqrt() {
                    lists[i].insert(j as u32);
                    lists[j].insert(i as u32);
                }
            }
            let want: Vec<Vec<u32>> = lists.into_iter().map(|l| l.into_iter().collect()).collect();
            let got = strength_graph(&a, blocks, theta);
            assert_eq!(got, NodeGraph::from_lists(&want), "theta {theta}");
            if theta > 0.0 {
                assert!(got.neighbours.len() < strength_graph(&a, blocks, 0.0).neighbours.len(), "theta drops couplings");
            }
        }
    }

    #[test]
    fn every_node_is_aggregated_and_aggregates_are_connected() {
        let graph = chain(10);
        let (agg, count) = aggregate(&graph);
        assert!(agg.iter().all(|&a| (a as usize) < count));
        // Pass 1 on a chain: 0 with its neighbour 1, then 2-3-4 around 3, 5-6-7 around 6.
        assert_eq!(&agg[..8], &[0, 0, 1, 1, 1, 2, 2, 2]);
        for a in 0..count as u32 {
            let members: Vec<usize> = (0..10).filter(|&i| agg[i] == a).collect();
            assert!(!members.is_empty());
            assert!(members.windows(2).all(|w| w[1] == w[0] + 1), "aggregate {a} is not contiguous: {members:?}");
        }
    }

    #[test]
    fn tentative_prolongator_reproduces_the_near_null_space() {
        // Six nodes on a line with two unknowns each and the three rigid-body modes.
        let blocks = Blocks { block: 2, nodes: 6 };
        let xs = [0.0, 0.3, 0.5, 1.0, 1.4, 2.0];
        let mut null = Vec::new();
        for x in xs {
            let y = 0.1 * x * x;
            null.extend_from_slice(&[1.0, 0.0, -y, 0.0, 1.0, x]);
        }
        let (agg, count) = aggregate(&chain(6));
        let (t, coarse) = tentative(&null, 3, blocks, &agg, count);
        // T B_c = B.
        for row in 0..12 {
            for c in 0..3 {
                let (cols, vals) = (t.row(row).col_indices().to_vec(), t.row(row).values().to_vec());
                let tb: f64 = cols.iter().zip(&vals).map(|(&j, &v)| v * coarse[(j as usize / 3) * 9 + (j as usize % 3) * 3 + c]).sum();
                assert!((tb - null[row * 3 + c]).abs() < 1e-13, "row {row} column {c}: {tb} vs {}", null[row * 3 + c]);
            }
        }
    }

    #[test]
    fn a_one_node_aggregate_keeps_its_translations_only() {
        let blocks = Blocks { block: 2, nodes: 1 };
        let null = vec![1.0, 0.0, -0.5, 0.0, 1.0, 0.25];
        let (t, coarse) = tentative(&null, 3, blocks, &[0], 1);
        assert_eq!(t.nnz(), 2, "the rotation column is dependent on one node");
        assert_eq!(coarse[8], 0.0);
    }
}
