//! The near-null spaces of the multigrid ([`super::amg`]): the vectors its tentative
//! prolongator (right, `B`) and restriction (left, `Bᴴ`) reproduce exactly on each
//! aggregate. Right: the rigid-body modes, which every Navier and peridynamic row
//! annihilates. Left: those modes relaxed on `aᵀ y = 0`, since a collocation matrix is
//! not symmetric and its left near-null vectors are not the rigid-body modes.

use super::aggregation::Blocks;
use super::layout::NodeLayout;
use super::csr::Csr;
use super::smoother::MAX_BLOCK;

/// The rigid-body modes at `layout` (unknowns × 3, row-major), positions centred and
/// scaled to unit size so that the rotation has the translations' magnitude; a
/// pressure unknown gets zeros (rigid motions carry no pressure). Without a layout,
/// the two translations of a two-unknowns-per-node system (`k = 2`).
pub(super) fn rigid_body_modes(n: usize, layout: Option<NodeLayout>) -> (Vec<f64>, usize) {
    let Some(layout) = layout.filter(|l| l.per_node >= 2 && l.positions.len() * l.per_node == n) else {
        let mut b = vec![0.0; n * 2];
        for i in 0..n {
            b[i * 2 + i % 2] = 1.0;
        }
        return (b, 2);
    };
    let count = layout.positions.len() as f64;
    let centre = layout.positions.iter().fold([0.0, 0.0], |c, p| [c[0] + p[0] / count, c[1] + p[1] / count]);
    let size =
        layout.positions.iter().map(|p| (p[0] - centre[0]).abs().max((p[1] - centre[1]).abs())).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    let mut b = vec![0.0; n * 3];
    for (node, p) in layout.positions.iter().enumerate() {
        let (x, y) = ((p[0] - centre[0]) / size, (p[1] - centre[1]) / size);
        let row = node * layout.per_node;
        b[row * 3..row * 3 + 3].copy_from_slice(&[1.0, 0.0, -y]);
        b[(row + 1) * 3..(row + 1) * 3 + 3].copy_from_slice(&[0.0, 1.0, x]);
    }
    (b, 3)
}

/// Symmetric Gauss–Seidel iterations that grow the finest level's left near-null space
/// (`left_near_null`): pyamg takes 4; on the Lame ring 2 did as well as 4 (pyamg on
/// our exported system: docs/notebook/2026-11-25-multigrid-symmetry-edges.md).
pub(super) const LEFT_NULL_ITERATIONS: usize = 2;

/// Near-null vectors of `aᵀ` grown from those of `a`: `iterations` symmetric block
/// Gauss–Seidel iterations (a forward and a backward sweep each) on `aᵀ y = 0` from
/// `y = null` (unknowns × `k`, row-major), `aᵀ`'s diagonal blocks `D_Iᵀ` inverted as
/// `(D_I⁺)ᵀ`. A collocation matrix is not symmetric, and its left near-null space is
/// not the rigid-body modes: the restriction built from these (pyamg's "improve
/// candidates" applied to `BH`, Olson & Schroder's nonsymmetric SA) cut the scattered
/// Lame ring's iterations in pyamg several-fold, far more than relaxing only `B`
/// (`benches/pyamg_left_null.py`; docs/notebook/2026-11-25-multigrid-symmetry-edges.md).
///
/// `aᵀ` is never formed: the residual `r = −aᵀ y` is kept up to date by scattering each
/// node's change through its rows of `a`, `r_j −= a_ij δ_i`, so a sweep is one serial
/// pass over `a` updating `k` vectors (a hybrid sweep by thread, as
/// `smoother::gauss_seidel` does, was no faster and cost the Lame ring iterations:
/// docs/notebook/2026-11-25-multigrid-symmetry-edges.md).
pub(super) fn left_near_null(a: &Csr, blocks: Blocks, inv_diag: &[f64], null: &[f64], k: usize, iterations: usize) -> Vec<f64> {
    let (b, n) = (blocks.block, a.nrows());
    let (ptr, idx, val) = (a.row_offsets(), a.col_indices(), a.values());
    let mut y = null.to_vec();
    let mut r = vec![0.0f64; n * k];
    let scatter = |r: &mut [f64], row: usize, d: &[f64]| {
        for (&j, &v) in idx[ptr[row]..ptr[row + 1]].iter().zip(&val[ptr[row]..ptr[row + 1]]) {
            for (c, dc) in d.iter().enumerate() {
                r[j as usize * k + c] -= v * dc;
            }
        }
    };
    for row in 0..n {
        scatter(&mut r, row, &y[row * k..(row + 1) * k]);
    }
    let mut visit = |node: usize| {
        let inv = &inv_diag[node * b * b..(node + 1) * b * b];
        let mut delta = [0.0f64; MAX_BLOCK * MAX_BLOCK];
        for m in 0..b {
            for c in 0..k {
                delta[m * k + c] = (0..b).map(|l| inv[l * b + m] * r[(node * b + l) * k + c]).sum();
            }
        }
        for m in 0..b {
            let (row, d) = (node * b + m, &delta[m * k..(m + 1) * k]);
            for c in 0..k {
                y[row * k + c] += d[c];
            }
            scatter(&mut r, row, d);
        }
    };
    for _ in 0..iterations {
        (0..blocks.nodes).for_each(&mut visit);
        (0..blocks.nodes).rev().for_each(&mut visit);
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::smoother::{gauss_seidel, inverse_diagonal_blocks, Sweep};

    #[test]
    fn rigid_body_modes_are_centred_translations_and_a_rotation() {
        let positions = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
        let (b, k) = rigid_body_modes(8, Some(NodeLayout { per_node: 2, positions: &positions, multipliers: 0 }));
        assert_eq!(k, 3);
        // Node 2 at (1, 1) from the centre, scaled by 1: u = (-y, x) = (-1, 1).
        assert_eq!(&b[4 * 3..4 * 3 + 3], &[1.0, 0.0, -1.0]);
        assert_eq!(&b[5 * 3..5 * 3 + 3], &[0.0, 1.0, 1.0]);
    }

    /// A nonsymmetric matrix with 2x2 nodal blocks: a convection-diffusion stencil on a
    /// ring of `nodes` nodes, coupled between the two components.
    fn ring(nodes: usize) -> Csr {
        let mut e = Vec::new();
        for i in 0..nodes {
            let (prev, next) = ((i + nodes - 1) % nodes, (i + 1) % nodes);
            for c in 0..2 {
                let row = 2 * i + c;
                e.push((row, row, 4.0 + c as f64));
                e.push((row, 2 * i + 1 - c, 0.7));
                e.push((row, 2 * prev + c, -2.5));
                e.push((row, 2 * next + c, -0.5 - 0.3 * c as f64));
                e.push((row, 2 * ((i + 7) % nodes) + 1 - c, 0.2));
            }
        }
        Csr::from_triplets(2 * nodes, 2 * nodes, &e)
    }

    /// The scatter form (no transpose formed) is block Gauss–Seidel on `aᵀ y = 0`: the
    /// same iterate as the sweeps of [`gauss_seidel`] on the formed transpose, to
    /// round-off (1e-12 of the vectors' size; a wrong block transpose, order or sign
    /// gives O(1) differences), and it lowers `‖aᵀ y‖`.
    #[test]
    fn left_near_null_is_gauss_seidel_on_the_transpose() {
        let (nodes, k) = (40, 3);
        let a = ring(nodes);
        let blocks = Blocks { block: 2, nodes };
        let null: Vec<f64> = (0..2 * nodes * k).map(|i| ((i * 37 % 11) as f64 - 5.0) / 5.0).collect();
        let inv = inverse_diagonal_blocks(&a, blocks);
        let y = left_near_null(&a, blocks, &inv, &null, k, 2);
        let at = a.transpose();
        let inv_t = inverse_diagonal_blocks(&at, blocks);
        let zero = vec![0.0; 2 * nodes];
        let mut copies = Vec::new();
        let product_norm = |v: &[f64]| {
            let mut out = vec![0.0; 2 * nodes];
            crate::linalg::csr::product(&at, v, &mut out);
            out.iter().map(|x| x * x).sum::<f64>().sqrt()
        };
        for c in 0..k {
            let mut z: Vec<f64> = (0..2 * nodes).map(|row| null[row * k + c]).collect();
            let before = product_norm(&z);
            for direction in [Sweep::Forward, Sweep::Backward, Sweep::Forward, Sweep::Backward] {
                gauss_seidel(&at, blocks, &inv_t, &zero, &mut z, direction, &mut copies);
            }
            let ours: Vec<f64> = (0..2 * nodes).map(|row| y[row * k + c]).collect();
            let worst = z.iter().zip(&ours).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(worst <= 1e-12 * z.iter().fold(1.0f64, |m, v| m.max(v.abs())), "column {c}: {worst:.1e}");
            assert!(product_norm(&ours) < 0.5 * before, "column {c}: |A^T y| {:.2e} from {before:.2e}", product_norm(&ours));
        }
    }
}
