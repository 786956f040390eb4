//! The force loop of explicit dynamics: each bond once where the weights allow it.
//!
//! A bond between free nodes `i < j` exerts `V_i f_ij` on `i` and `V_j f_ji = -V_i f_ij`
//! on `j` whenever `V_i c_ij = V_j c_ji` (both laws of [`super::dynamics`] are odd in
//! `(xi, eta)`; every weight rule but the compatible one is symmetric, see
//! [`super::weights`]). So the loop visits the bonds of `i` to nodes of higher index
//! only (families are sorted: a suffix of the family, bonds to the collar included) and
//! adds `g = V_i f_ij` to node `i` and `-g` to node `j`: half the bonds of the directed
//! loop, each with one more scatter. With weights that are not symmetric the same loop
//! visits every bond from both ends ("directed") and scatters nothing. The workers'
//! shares are contiguous ranges of nodes with about equal numbers of bonds, each
//! summing into its own buffer, reused between evaluations.

use super::block::{Columns, Kernel, Layout, BLOCK};
pub use super::block::{Flagged, PairState};
use super::family::Families;
use super::nodes::PdNodes;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::Mutex;

/// Largest relative difference `|V_i c_ij - V_j c_ji| / |V_i c_ij|` taken as symmetric:
/// the round-off of the moment solves (the symmetric rules leave interior pairs as
/// their solves give them, [`super::weights`]). The pair loop uses `V_i c_ij` for both
/// directions, so the force on `j` moves by at most this share of the bond's.
pub const SYMMETRY_TOLERANCE: f64 = 1e-12;

/// The force loop's bonds of one discretisation (module docs).
pub struct Pairs {
    /// Per free node, the first bond the loop visits: its first bond to a node of
    /// higher index, or its first bond when directed.
    first: Vec<usize>,
    /// Every bond from both ends (the weights are not symmetric).
    directed: bool,
    /// Free nodes of each share.
    shares: Vec<Range<usize>>,
    /// Per share, a force buffer over the free nodes (reused).
    buffers: Mutex<Vec<Vec<[f64; 2]>>>,
    /// An elastic energy the caller kept from a sum, and where it was evaluated:
    /// `(t, the address of u, E)` ([`Pairs::keep_energy`]).
    kept: Mutex<Option<(f64, usize, f64)>>,
}

impl Pairs {
    /// The loop over `families` with `coefficients`: directed when some pair of free
    /// nodes has `V_i c_ij != V_j c_ji` beyond [`SYMMETRY_TOLERANCE`].
    pub fn new(nodes: &PdNodes, families: &Families, coefficients: &[f64]) -> Pairs {
        let free = nodes.free;
        let upper: Vec<usize> =
            (0..free).into_par_iter().map(|i| families.range(i).start + families.of(i).partition_point(|&j| j as usize <= i)).collect();
        let symmetric = (0..free).into_par_iter().all(|i| {
            (upper[i]..families.range(i).end).all(|b| {
                let j = families.neighbour(b) as usize;
                if j >= free {
                    return true;
                }
                let Ok(k) = families.of(j).binary_search(&(i as u32)) else { return false };
                let (forward, back) = (nodes.volumes[i] * coefficients[b], nodes.volumes[j] * coefficients[families.range(j).start + k]);
                (forward - back).abs() <= SYMMETRY_TOLERANCE * forward.abs()
            })
        });
        let first = if symmetric { upper } else { (0..free).map(|i| families.range(i).start).collect() };
        // Contiguous shares of about equal pair counts, one per worker.
        let workers = rayon::current_num_threads().max(1);
        let total: usize = (0..free).map(|i| families.range(i).end - first[i]).sum();
        let mut shares = Vec::with_capacity(workers);
        let (mut start, mut counted) = (0, 0);
        for (i, &from) in first.iter().enumerate() {
            counted += families.range(i).end - from;
            if counted * workers >= total * (shares.len() + 1) && shares.len() + 1 < workers {
                shares.push(start..i + 1);
                start = i + 1;
            }
        }
        shares.push(start..free);
        Pairs { first, directed: !symmetric, shares, buffers: Mutex::new(Vec::new()), kept: Mutex::new(None) }
    }

    /// Whether every bond is visited from both ends (the weights are not symmetric).
    pub fn directed(&self) -> bool {
        self.directed
    }

    /// The bonds of free node `i` the loop visits: those to nodes of higher index, or
    /// all when directed.
    pub fn upper(&self, families: &Families, i: usize) -> Range<usize> {
        self.first[i]..families.range(i).end
    }

    /// `F_i = sum_{j > i} g_ij - sum_{j < i} g_ji` over the pairs of the state `at`
    /// (directed: `F_i = sum_j g_ij`), `(g, flag, e) = law(c_ij, xi, eta, V_i)` for
    /// bond `b` of node `i` to node `j` (collar nodes take nothing), the bonds
    /// that `law` flags with what the loop read of them ([`Flagged`]), in node and bond
    /// order, and the sum of the energies `e` as [`Pairs::energy`] counts them. Bonds go
    /// in blocks of [`BLOCK`] in the `layout` ([`super::block`]).
    pub fn sum<L>(&self, families: &Families, at: &PairState, (law, layout): (L, Layout)) -> (Vec<[f64; 2]>, Vec<Flagged>, f64)
    where
        L: Fn(f64, [f64; 2], [f64; 2], f64) -> ([f64; 2], bool, f64) + Sync,
    {
        let free = self.first.len();
        let kernel = Kernel::new(layout);
        let mut buffers = std::mem::take(&mut *self.buffers.lock().expect("no panic holds it"));
        buffers.resize_with(self.shares.len(), || vec![[0.0; 2]; free]);
        let reached: Vec<(Vec<Flagged>, f64)> = buffers
            .par_iter_mut()
            .zip(&self.shares)
            .map(|(force, share)| {
                force.iter_mut().for_each(|f| *f = [0.0; 2]);
                let (mut reached, mut energy) = (Vec::new(), 0.0);
                let mut columns = Box::<Columns>::default();
                for i in share.clone() {
                    let upper = self.upper(families, i);
                    let js = &families.of(i)[upper.start - families.range(i).start..];
                    for (block, js) in js.chunks(BLOCK).enumerate() {
                        let start = upper.start + BLOCK * block;
                        let bonds = (i, start, js);
                        let (g, mut flags, e) = if self.directed {
                            kernel.sum::<false, _>(*at, bonds, force, &law, &mut columns)
                        } else {
                            kernel.sum::<true, _>(*at, bonds, force, &law, &mut columns)
                        };
                        force[i] = [force[i][0] + g[0], force[i][1] + g[1]];
                        energy += e;
                        while flags != 0 {
                            let k = flags.trailing_zeros() as usize;
                            reached.push(Flagged::read(at, i, start + k, js[k] as usize));
                            flags &= flags - 1;
                        }
                    }
                }
                (reached, energy)
            })
            .collect();
        let total: Vec<[f64; 2]> =
            (0..free).into_par_iter().map(|i| buffers.iter().fold([0.0; 2], |s, f| [s[0] + f[i][0], s[1] + f[i][1]])).collect();
        *self.buffers.lock().expect("no panic holds it") = buffers;
        let energy = reached.iter().map(|r| r.1).sum();
        (total, reached.into_iter().flat_map(|r| r.0).collect(), energy)
    }

    /// Keep the elastic energy `e` of the displacements `u` at time `t` (a sum's, with
    /// whatever the caller adds), for [`Pairs::kept_energy`].
    pub fn keep_energy(&self, t: f64, u: &[f64], e: f64) {
        *self.kept.lock().expect("no panic holds it") = Some((t, u.as_ptr() as usize, e));
    }

    /// Add `de` to the kept energy when it is of `u` at `t` (bonds broken after the sum
    /// took theirs away).
    pub fn change_kept_energy(&self, t: f64, u: &[f64], de: f64) {
        if let Some(k) = self.kept.lock().expect("no panic holds it").as_mut().filter(|k| (k.0, k.1) == (t, u.as_ptr() as usize)) {
            k.2 += de;
        }
    }

    /// The kept energy, when it is of the displacements `u` at time `t` (the same vector,
    /// not changed since: the callers keep it from the evaluation that ends a step).
    pub fn kept_energy(&self, t: f64, u: &[f64]) -> Option<f64> {
        self.kept.lock().expect("no panic holds it").filter(|k| (k.0, k.1) == (t, u.as_ptr() as usize)).map(|k| k.2)
    }

    /// `E = 1/2 sum_i V_i sum_j w(c_ij, xi, eta)` at the state `at` over the bonds of
    /// free nodes `i` to nodes `j`: a pair of free nodes counted once (`V_i w_ij = V_j
    /// w_ji`), a bond to the collar half (the collar's own half is not counted), every
    /// bond half when directed.
    pub fn energy(&self, families: &Families, at: &PairState, w: impl Fn(f64, [f64; 2], [f64; 2]) -> f64 + Sync) -> f64 {
        self.shares
            .par_iter()
            .map(|nodes| {
                nodes
                    .clone()
                    .map(|i| {
                        let upper = self.upper(families, i);
                        let js = &families.of(i)[upper.start - families.range(i).start..];
                        at.volumes[i] * node_energy(*at, (i, upper.start, js), self.directed, &w)
                    })
                    .sum::<f64>()
            })
            .sum()
    }
}

/// `sum_k share_k w(c, xi, eta)` over bonds `start + k` of node `i` to `js[k]`, `share`
/// 1 for a free `j` and 1/2 for the collar, 1/2 for all when `directed` ([`Pairs::energy`];
/// plain slices for the reason of [`super::block`]'s fused layout).
fn node_energy(at: PairState, (i, start, js): (usize, usize, &[u32]), directed: bool, w: &impl Fn(f64, [f64; 2], [f64; 2]) -> f64) -> f64 {
    let PairState { positions: x, u, prescribed, coefficients, .. } = at;
    let free = x.len() - prescribed.len();
    let (xi, ui) = (x[i], [u[2 * i], u[2 * i + 1]]);
    let (mut pairs, mut halves) = (0.0, 0.0);
    for (&j, &c) in js.iter().zip(&coefficients[start..start + js.len()]) {
        let j = j as usize;
        let uj = if j < free { [u[2 * j], u[2 * j + 1]] } else { prescribed[j - free] };
        let e = w(c, [x[j][0] - xi[0], x[j][1] - xi[1]], [uj[0] - ui[0], uj[1] - ui[1]]);
        if j < free && !directed {
            pairs += e;
        } else {
            halves += e;
        }
    }
    pairs + 0.5 * halves
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::peridynamics::test_case::plate_bonds;

    /// On the clamped plate (free nodes, a collar, symmetric weights `c_ij = V_j /
    /// |xi|^3`): the pair sum is the directed sum `V_i sum_j c_ij (xi . eta) xi` to
    /// round-off (1e-12 of the largest force: sums of about 30 terms), every flagged
    /// bond comes back once, the loop's energy is the energy pass's, and with weights
    /// made asymmetric the loop is directed and again gives the directed sums.
    #[test]
    fn the_pair_sum_is_the_directed_sum() {
        let (_, nodes, families, c, skewed) = plate_bonds();
        let x = &nodes.positions;
        let pairs = Pairs::new(&nodes, &families, &c);
        assert!(!pairs.directed(), "V_i c_ij = V_i V_j / |xi|^3 is symmetric");
        let u: Vec<f64> = x[..nodes.free].iter().flat_map(|p| [(3.0 * p[0]).sin(), p[0] * p[1]]).collect();
        let prescribed: Vec<[f64; 2]> = x[nodes.free..].iter().map(|p| [0.1 * p[1], -0.2 * p[0]]).collect();
        let at = PairState { positions: x, u: &u, prescribed: &prescribed, coefficients: &c, volumes: &nodes.volumes };
        let law = |c: f64, xi: [f64; 2], eta: [f64; 2], vi: f64| {
            let p = xi[0] * eta[0] + xi[1] * eta[1];
            ([vi * c * p * xi[0], vi * c * p * xi[1]], p > 0.0, 0.5 * vi * c * p * p)
        };
        let (forces, flagged, energy) = pairs.sum(&families, &at, (law, Layout::Fused));
        // The loop's energy is the energy pass's (another order of the same terms).
        let w = |c: f64, xi: [f64; 2], eta: [f64; 2]| law(c, xi, eta, 1.0).2;
        let pass = pairs.energy(&families, &at, w);
        assert!(energy > 0.0 && (energy - pass).abs() <= 1e-12 * pass, "loop {energy:e}, pass {pass:e}");
        let displacement = |j: usize| if j < nodes.free { [u[2 * j], u[2 * j + 1]] } else { prescribed[j - nodes.free] };
        let directed_force = |i: usize, c: &[f64]| {
            let mut f = [0.0; 2];
            for (b, &j) in families.range(i).zip(families.of(i)) {
                let j = j as usize;
                let (uj, ui) = (displacement(j), displacement(i));
                let (g, _, _) = law(c[b], [x[j][0] - x[i][0], x[j][1] - x[i][1]], [uj[0] - ui[0], uj[1] - ui[1]], nodes.volumes[i]);
                f = [f[0] + g[0], f[1] + g[1]];
            }
            f
        };
        let (mut largest, mut error) = (0.0f64, 0.0f64);
        for (i, sum) in forces.iter().enumerate().take(nodes.free) {
            let f = directed_force(i, &c);
            largest = largest.max(f[0].abs()).max(f[1].abs());
            error = error.max((f[0] - sum[0]).abs()).max((f[1] - sum[1]).abs());
        }
        assert!(error <= 1e-12 * largest, "pair sum off by {error:e} of {largest:e}");
        // The flagged bonds are the upper bonds with p > 0, each once, in order.
        let expected: Vec<(usize, usize)> = (0..nodes.free)
            .flat_map(|i| pairs.upper(&families, i).map(move |b| (i, b)))
            .filter(|&(i, b)| {
                let j = families.neighbour(b) as usize;
                let (uj, ui) = (displacement(j), displacement(i));
                let p = (x[j][0] - x[i][0]) * (uj[0] - ui[0]) + (x[j][1] - x[i][1]) * (uj[1] - ui[1]);
                p > 0.0
            })
            .collect();
        assert!(!expected.is_empty() && expected.len() < families.bonds() / 2);
        let flagged: Vec<(usize, usize)> = flagged
            .iter()
            .map(|f| {
                let j = families.neighbour(f.bond) as usize;
                let (uj, ui) = (displacement(j), displacement(f.node));
                let (xi, eta) = ([x[j][0] - x[f.node][0], x[j][1] - x[f.node][1]], [uj[0] - ui[0], uj[1] - ui[1]]);
                assert_eq!((f.neighbour, f.coefficient, f.xi, f.eta), (j, c[f.bond], xi, eta), "what the loop read");
                (f.node, f.bond)
            })
            .collect();
        assert_eq!(flagged, expected);
        // One bond's coefficient off by 1e-9 of itself: not symmetric, so every bond is
        // visited from both ends, and the sum is again the directed one.
        let directed = Pairs::new(&nodes, &families, &skewed);
        assert!(directed.directed());
        let at = PairState { coefficients: &skewed, ..at };
        let (forces, _, energy) = directed.sum(&families, &at, (law, Layout::Columns));
        let pass = directed.energy(&families, &at, w);
        assert!((energy - pass).abs() <= 1e-12 * pass, "directed: loop {energy:e}, pass {pass:e}");
        for (i, sum) in forces.iter().enumerate().take(nodes.free) {
            let f = directed_force(i, &skewed);
            assert!((f[0] - sum[0]).abs().max((f[1] - sum[1]).abs()) <= 1e-12 * largest, "directed sum at node {i}");
        }
    }
}
