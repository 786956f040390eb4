//! The coarse spaces of smoothed aggregation ([`super::amg`]): the strength graph
//! between nodes, aggregates of nodes, and the tentative prolongator that carries the
//! near-null space (rigid-body modes) exactly onto each aggregate.
//!
//! Vaněk, Mandel, Brezina, "Algebraic multigrid by smoothed aggregation for second and
//! fourth order elliptic problems", *Computing* 56 (1996) 179–196, §3; the three
//! aggregation passes follow their Algorithm 1 (as in pyamg's `standard_aggregation`).

use nalgebra::DMatrix;
use nalgebra_sparse::CsrMatrix;

/// Unknowns of a level grouped by node: `block` consecutive unknowns per node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Blocks {
    /// Unknowns per node (2 on the finest Navier level, the number of near-null
    /// vectors on coarse levels).
    pub block: usize,
    /// Nodes (`unknowns / block`).
    pub nodes: usize,
}

/// The node graph of `a`: `J` is a neighbour of `I` when some entry couples an unknown
/// of `I` with one of `J` and its block is strong,
/// `‖A_IJ‖_F ≥ θ √(‖A_II‖_F ‖A_JJ‖_F)` (Vaněk et al. eq. 3.1 with block norms), in
/// either direction: collocation stencils are not symmetric (`j` in the support of `i`
/// does not put `i` in that of `j`), and aggregates are built on the symmetrised graph.
/// Returned as sorted adjacency lists without the node itself.
pub fn strength_graph(a: &CsrMatrix<f64>, blocks: Blocks, theta: f64) -> Vec<Vec<u32>> {
    let b = blocks.block;
    let (ptr, idx, val) = (a.row_offsets(), a.col_indices(), a.values());
    // Squared block norms, node by node, as (neighbour, ‖A_IJ‖²) lists.
    let mut norms: Vec<Vec<(u32, f64)>> = vec![Vec::new(); blocks.nodes];
    let mut diag = vec![0.0f64; blocks.nodes];
    for (node, list) in norms.iter_mut().enumerate() {
        for row in node * b..(node + 1) * b {
            for k in ptr[row]..ptr[row + 1] {
                let other = (idx[k] / b) as u32;
                if other as usize == node {
                    diag[node] += val[k] * val[k];
                    continue;
                }
                list.push((other, val[k] * val[k]));
            }
        }
        list.sort_unstable_by_key(|e| e.0);
        list.dedup_by(|next, kept| {
            if next.0 == kept.0 {
                kept.1 += next.1;
                true
            } else {
                false
            }
        });
    }
    let mut graph: Vec<Vec<u32>> = vec![Vec::new(); blocks.nodes];
    for (node, list) in norms.iter().enumerate() {
        for &(other, n2) in list {
            // ‖A_IJ‖ ≥ θ √(‖A_II‖ ‖A_JJ‖)  ⇔  ‖A_IJ‖⁴ ≥ θ⁴ ‖A_II‖² ‖A_JJ‖².
            if theta == 0.0 || n2 * n2 >= theta.powi(4) * diag[node] * diag[other as usize] {
                graph[node].push(other);
                graph[other as usize].push(node as u32);
            }
        }
    }
    for list in &mut graph {
        list.sort_unstable();
        list.dedup();
    }
    graph
}

/// Aggregate of every node (`0..count`), from the node graph:
/// 1. a node whose neighbours are all free starts an aggregate with them;
/// 2. a free node joins the aggregate of its first aggregated neighbour;
/// 3. what is left (nodes whose neighbours were taken in pass 2) forms aggregates with
///    its free neighbours.
///
/// Every node ends in an aggregate; an isolated node is an aggregate of its own.
pub fn aggregate(graph: &[Vec<u32>]) -> (Vec<u32>, usize) {
    const FREE: u32 = u32::MAX;
    let n = graph.len();
    let mut agg = vec![FREE; n];
    let mut count = 0u32;
    for i in 0..n {
        if agg[i] != FREE || graph[i].iter().any(|&j| agg[j as usize] != FREE) {
            continue;
        }
        agg[i] = count;
        for &j in &graph[i] {
            agg[j as usize] = count;
        }
        count += 1;
    }
    let first_pass = agg.clone();
    for i in 0..n {
        if agg[i] == FREE {
            if let Some(&j) = graph[i].iter().find(|&&j| first_pass[j as usize] != FREE) {
                agg[i] = first_pass[j as usize];
            }
        }
    }
    for i in 0..n {
        if agg[i] != FREE {
            continue;
        }
        agg[i] = count;
        for &j in &graph[i] {
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
pub fn tentative(null: &[f64], k: usize, blocks: Blocks, agg: &[u32], count: usize) -> (CsrMatrix<f64>, Vec<f64>) {
    let b = blocks.block;
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); count];
    for (node, &a) in agg.iter().enumerate() {
        members[a as usize].push(node);
    }
    // Q entries by fine unknown: (coarse column, value).
    let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); blocks.nodes * b];
    let mut coarse = vec![0.0; count * k * k];
    for (a, nodes) in members.iter().enumerate() {
        let unknowns: Vec<usize> = nodes.iter().flat_map(|&n| n * b..(n + 1) * b).collect();
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
                if q[(local, c)] != 0.0 {
                    rows[u].push((a * k + c, q[(local, c)]));
                }
            }
        }
        for i in 0..k {
            for j in 0..k {
                coarse[(a * k + i) * k + j] = r[(i, j)];
            }
        }
    }
    let mut offsets = Vec::with_capacity(rows.len() + 1);
    offsets.push(0);
    let (mut cols, mut vals) = (Vec::new(), Vec::new());
    for row in rows {
        for (c, v) in row {
            cols.push(c);
            vals.push(v);
        }
        offsets.push(cols.len());
    }
    let t = CsrMatrix::try_from_csr_data(blocks.nodes * b, count * k, offsets, cols, vals)
        .expect("tentative prolongator: columns are sorted within each row by construction");
    (t, coarse)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1D chain of `n` nodes (tridiagonal blocks).
    fn chain(n: usize) -> Vec<Vec<u32>> {
        (0..n).map(|i| [i.wrapping_sub(1), i + 1].into_iter().filter(|&j| j < n).map(|j| j as u32).collect()).collect()
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
                let tb: f64 = cols.iter().zip(&vals).map(|(&j, &v)| v * coarse[(j / 3) * 9 + (j % 3) * 3 + c]).sum();
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
