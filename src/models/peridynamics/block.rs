//! One block of the force loop: up to [`BLOCK`] bonds of node `i`, `(g, flag, e) =
//! law(c_ij, xi, eta, V_i)` per bond, `g` summed on `i` and (pairs) taken from `j`, the
//! flags returned as the bits of a `u64`, the bonds' energies `e` summed, a pair's whole
//! and a bond's to the collar or seen from both ends half ([`super::pairs`]).
//!
//! Two layouts of the same operations, chosen by the law ([`Layout`]):
//! - **fused**: gather, law and scatter in one loop per bond. The linear law's few
//!   products make the loop bound by its loads; columns would only add stores.
//! - **columns**: the bond vectors gathered into columns, the law over the columns (a
//!   loop of arithmetic alone, which the compiler vectorises, roots and divisions
//!   included), the forces scattered.
//!
//! Both are compiled twice, for the baseline x86-64 and for AVX2 (three-operand
//! instructions; four lanes in the columns' law), the second taken where the CPU has
//! it. Neither fuses a multiply and an add, and the sums run in bond order in both, so
//! the results are the same to the bit whichever runs. Measured: docs/notebook/2026-11-30-block-kernels.md.

/// Bonds per block (the flags of a block fit a `u64`).
pub const BLOCK: usize = 64;

/// A law of the force loop: `(g, flag, e) = law(c_ij, xi, eta, V_i)`: the force `g = V_i
/// f_ij`, whether the bond is flagged, and its energy `e = V_i w_ij` (0 where the loop does
/// not sum the energy).
pub trait BondLaw: Fn(f64, [f64; 2], [f64; 2], f64) -> ([f64; 2], bool, f64) {}
impl<F: Fn(f64, [f64; 2], [f64; 2], f64) -> ([f64; 2], bool, f64)> BondLaw for F {}

/// How a block is evaluated (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// One loop per bond: for laws of a few products (the linear law).
    Fused,
    /// Gather, law over columns, scatter: for laws with roots or divisions (the
    /// bond-stretch law), whose arithmetic then runs in vector lanes.
    Columns,
}

/// The block kernel of one force evaluation: its [`Layout`] and whether the CPU has AVX2
/// (asked once per evaluation).
#[derive(Clone, Copy, Debug)]
pub struct Kernel {
    layout: Layout,
    avx2: bool,
}

impl Kernel {
    /// The kernel of `layout` for this CPU.
    pub fn new(layout: Layout) -> Self {
        #[cfg(target_arch = "x86_64")]
        let avx2 = std::arch::is_x86_feature_detected!("avx2");
        #[cfg(not(target_arch = "x86_64"))]
        let avx2 = false;
        Kernel { layout, avx2 }
    }

    /// The sum of `law`'s forces over bonds `start + k` of node `i` to `js[k]` (at most
    /// [`BLOCK`]), each subtracted from `force[j]` when `j` is free and `SCATTER`, the
    /// flags (bit `k`: bond `start + k`), and the sum of the energies, each whole where
    /// `j` is free and `SCATTER` (the pair's) and half otherwise. `columns` is the
    /// caller's scratch.
    #[inline]
    pub fn sum<const SCATTER: bool, L: BondLaw>(
        self,
        at: PairState,
        bonds: (usize, usize, &[u32]),
        force: &mut [[f64; 2]],
        law: &L,
        columns: &mut Columns,
    ) -> ([f64; 2], u64, f64) {
        debug_assert!(bonds.2.len() <= BLOCK);
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // Safety: the CPU has AVX2 (`Kernel::new` asked it).
            return unsafe {
                match self.layout {
                    Layout::Fused => avx2::<SCATTER, false, L>(at, bonds, force, law, columns),
                    Layout::Columns => avx2::<SCATTER, true, L>(at, bonds, force, law, columns),
                }
            };
        }
        match self.layout {
            Layout::Fused => baseline::<SCATTER, false, L>(at, bonds, force, law, columns),
            Layout::Columns => baseline::<SCATTER, true, L>(at, bonds, force, law, columns),
        }
    }
}

/// What a block reads ([`super::pairs::Pairs::sum`]): node positions, the free nodes' displacements
/// (interleaved), the collar's prescribed ones (node `free + k` is `prescribed[k]`), the
/// bond coefficients and the volumes.
#[derive(Clone, Copy)]
pub struct PairState<'a> {
    /// Positions of all nodes.
    pub positions: &'a [[f64; 2]],
    /// Displacements of the free nodes, interleaved.
    pub u: &'a [f64],
    /// Displacements of the collar nodes.
    pub prescribed: &'a [[f64; 2]],
    /// `c_ij` per bond.
    pub coefficients: &'a [f64],
    /// `V_i` per node.
    pub volumes: &'a [f64],
}

/// A bond the force loop flagged, with what it read of it: bond `bond` of free node
/// `node` to `neighbour`, its coefficient and `(xi, eta)`. Read while the block's data
/// is in the cache, so that the breaking after the step need not fetch it again
/// ([`super::dynamics`], [`super::pairs::Pairs::sum`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Flagged {
    /// The free node.
    pub node: usize,
    /// The bond, an index into the families.
    pub bond: usize,
    /// The node at the bond's other end.
    pub neighbour: usize,
    /// `c_ij` as the loop read it.
    pub coefficient: f64,
    /// `x_j - x_i`.
    pub xi: [f64; 2],
    /// `u_j - u_i` at the evaluated state.
    pub eta: [f64; 2],
}

impl Flagged {
    /// Bond `b` of free node `i` to node `j` at the state `at`.
    pub(super) fn read(at: &PairState, i: usize, b: usize, j: usize) -> Flagged {
        let (xi, eta) = bond_vectors(at.positions, at.u, at.prescribed, i, j);
        Flagged { node: i, bond: b, neighbour: j, coefficient: at.coefficients[b], xi, eta }
    }
}

/// One block's bonds as columns: `xi` and `eta` in, the law's `g` and flag out.
pub struct Columns {
    xi: [[f64; BLOCK]; 2],
    eta: [[f64; BLOCK]; 2],
    g: [[f64; BLOCK]; 2],
    e: [f64; BLOCK],
    flag: [bool; BLOCK],
}

impl Default for Columns {
    fn default() -> Self {
        Columns { xi: [[0.0; BLOCK]; 2], eta: [[0.0; BLOCK]; 2], g: [[0.0; BLOCK]; 2], e: [0.0; BLOCK], flag: [false; BLOCK] }
    }
}

// The compiled kernels: a layout (`COLUMNS`) on the baseline and on AVX2. Each is its
// own never-inlined function: with a call or a push in the loop's function the compiler
// kept the sums on the stack (1.5-2x slower, docs/notebook/2026-11-29-bond-pairs.md).

/// The block in the layout `COLUMNS` (the fused one otherwise), baseline x86-64.
#[inline(never)]
fn baseline<const SCATTER: bool, const COLUMNS: bool, L: BondLaw>(
    at: PairState,
    bonds: (usize, usize, &[u32]),
    force: &mut [[f64; 2]],
    law: &L,
    columns: &mut Columns,
) -> ([f64; 2], u64, f64) {
    in_layout::<SCATTER, COLUMNS, L>(at, bonds, force, law, columns)
}

/// [`baseline`] for AVX2.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline(never)]
unsafe fn avx2<const SCATTER: bool, const COLUMNS: bool, L: BondLaw>(
    at: PairState,
    bonds: (usize, usize, &[u32]),
    force: &mut [[f64; 2]],
    law: &L,
    columns: &mut Columns,
) -> ([f64; 2], u64, f64) {
    in_layout::<SCATTER, COLUMNS, L>(at, bonds, force, law, columns)
}

/// [`in_columns`] when `COLUMNS`, else [`fused`].
#[inline(always)]
fn in_layout<const SCATTER: bool, const COLUMNS: bool, L: BondLaw>(
    at: PairState,
    bonds: (usize, usize, &[u32]),
    force: &mut [[f64; 2]],
    law: &L,
    columns: &mut Columns,
) -> ([f64; 2], u64, f64) {
    if COLUMNS {
        in_columns::<SCATTER, L>(at, bonds, force, law, columns)
    } else {
        fused::<SCATTER, L>(at, bonds, force, law)
    }
}

/// `(xi, eta)` of the bond from free node `i` to node `j`: positions `x`, free nodes'
/// displacements `u` (interleaved), the collar's `prescribed` (node `free + k` is
/// `prescribed[k]`, `free = x.len() - prescribed.len()`).
#[inline(always)]
pub fn bond_vectors(x: &[[f64; 2]], u: &[f64], prescribed: &[[f64; 2]], i: usize, j: usize) -> ([f64; 2], [f64; 2]) {
    let free = x.len() - prescribed.len();
    let uj = if j < free { [u[2 * j], u[2 * j + 1]] } else { prescribed[j - free] };
    let ui = [u[2 * i], u[2 * i + 1]];
    ([x[j][0] - x[i][0], x[j][1] - x[i][1]], [uj[0] - ui[0], uj[1] - ui[1]])
}

/// `u_j`: a free node's from `u` (the free nodes' pairs), a collar node's from
/// `prescribed`.
#[inline(always)]
fn displacement(u: &[[f64; 2]], prescribed: &[[f64; 2]], free: usize, j: usize) -> [f64; 2] {
    if j < free {
        u[j]
    } else {
        prescribed[j - free]
    }
}

/// The fused layout: gather, law and scatter per bond. The state comes as plain slices
/// and the law as a function of numbers, and the loop has no branch on the flags: the
/// loads stay out of the loop and the sums in registers.
#[inline(always)]
fn fused<const SCATTER: bool, L: BondLaw>(
    at: PairState,
    (i, start, js): (usize, usize, &[u32]),
    force: &mut [[f64; 2]],
    law: &L,
) -> ([f64; 2], u64, f64) {
    let PairState { positions: x, u, prescribed, coefficients, volumes } = at;
    let free = x.len() - prescribed.len();
    // One bounds check per node's displacement (the interleaved `u` as pairs).
    let u = u.as_chunks::<2>().0;
    let (xi, ui, vi) = (x[i], u[i], volumes[i]);
    let c = &coefficients[start..start + js.len()];
    let (mut f, mut flags, mut energy) = ([0.0, 0.0], 0u64, 0.0);
    for (k, (&j, &c)) in js.iter().zip(c).enumerate() {
        let j = j as usize;
        let uj = displacement(u, prescribed, free, j);
        let (g, flag, e) = law(c, [x[j][0] - xi[0], x[j][1] - xi[1]], [uj[0] - ui[0], uj[1] - ui[1]], vi);
        f[0] += g[0];
        f[1] += g[1];
        energy += share::<SCATTER>(j < free) * e;
        if let Some(fj) = force.get_mut(j).filter(|_| SCATTER) {
            fj[0] -= g[0];
            fj[1] -= g[1];
        }
        flags |= u64::from(flag) << k;
    }
    (f, flags, energy)
}

/// The share of a bond's energy in the sum: a pair's whole (`j` free, visited once:
/// `SCATTER`), half of a bond to the collar (the collar's own half is not counted) or of
/// a bond seen from both ends.
#[inline(always)]
fn share<const SCATTER: bool>(free: bool) -> f64 {
    if SCATTER && free {
        1.0
    } else {
        0.5
    }
}

/// The columns layout: the bond vectors gathered, the law over the columns (no loads
/// but the columns', so it vectorises), the forces scattered and summed in bond order.
#[inline(always)]
fn in_columns<const SCATTER: bool, L: BondLaw>(
    at: PairState,
    (i, start, js): (usize, usize, &[u32]),
    force: &mut [[f64; 2]],
    law: &L,
    columns: &mut Columns,
) -> ([f64; 2], u64, f64) {
    let PairState { positions: x, u, prescribed, coefficients, volumes } = at;
    let free = x.len() - prescribed.len();
    let n = js.len().min(BLOCK);
    let (js, c) = (&js[..n], &coefficients[start..start + n]);
    let u = u.as_chunks::<2>().0;
    let (xi, ui, vi) = (x[i], u[i], volumes[i]);
    let Columns { xi: cx, eta: ce, g: cg, e: cw, flag: cf } = columns;
    for (k, &j) in js.iter().enumerate() {
        let j = j as usize;
        let uj = displacement(u, prescribed, free, j);
        cx[0][k] = x[j][0] - xi[0];
        cx[1][k] = x[j][1] - xi[1];
        ce[0][k] = uj[0] - ui[0];
        ce[1][k] = uj[1] - ui[1];
    }
    for k in 0..n {
        let (g, flag, e) = law(c[k], [cx[0][k], cx[1][k]], [ce[0][k], ce[1][k]], vi);
        cg[0][k] = g[0];
        cg[1][k] = g[1];
        cw[k] = e;
        cf[k] = flag;
    }
    let (mut f, mut energy) = ([0.0, 0.0], 0.0);
    for (k, &j) in js.iter().enumerate() {
        let g = [cg[0][k], cg[1][k]];
        f[0] += g[0];
        f[1] += g[1];
        energy += share::<SCATTER>((j as usize) < free) * cw[k];
        if let Some(fj) = force.get_mut(j as usize).filter(|_| SCATTER) {
            fj[0] -= g[0];
            fj[1] -= g[1];
        }
    }
    let mut flags = 0u64;
    if cf[..n].iter().any(|&b| b) {
        for (k, &b) in cf[..n].iter().enumerate() {
            flags |= u64::from(b) << k;
        }
    }
    (f, flags, energy)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every compiled kernel gives the same forces, flags and energy to the bit, on a block of
    /// 61 bonds (a partial block), with the bond-stretch law's roots and division and
    /// collar nodes among the neighbours.
    #[test]
    fn every_kernel_gives_the_same_bits() {
        let n = 80;
        let x: Vec<[f64; 2]> = (0..n).map(|k| [(k as f64 * 0.37).sin(), (k as f64 * 0.91).cos()]).collect();
        let free = 70;
        let u: Vec<f64> = (0..2 * free).map(|k| 1e-3 * (k as f64 * 1.3).sin()).collect();
        let prescribed: Vec<[f64; 2]> = (free..n).map(|k| [1e-3 * k as f64, -2e-4]).collect();
        let coefficients: Vec<f64> = (0..n).map(|k| if k % 7 == 0 { 0.0 } else { 1.0 + k as f64 }).collect();
        let volumes = vec![0.5; n];
        let at = PairState { positions: &x, u: &u, prescribed: &prescribed, coefficients: &coefficients, volumes: &volumes };
        let js: Vec<u32> = (19..80).collect();
        let law = |c: f64, xi: [f64; 2], eta: [f64; 2], vi: f64| {
            let r = (xi[0] * xi[0] + xi[1] * xi[1]).sqrt();
            let y = [xi[0] + eta[0], xi[1] + eta[1]];
            let ry = (y[0] * y[0] + y[1] * y[1]).sqrt();
            let k = vi * c * r * r * (ry - r) / ry;
            ([k * y[0], k * y[1]], (c != 0.0) & (ry - r >= 1e-4 * r), 0.5 * vi * c * r * r * (ry - r) * (ry - r))
        };
        let mut columns = Columns::default();
        let mut results = Vec::new();
        for layout in [Layout::Fused, Layout::Columns] {
            for avx2 in [false, Kernel::new(layout).avx2] {
                let kernel = Kernel { layout, avx2 };
                let mut force = vec![[0.0; 2]; free];
                let (g, flags, energy) = kernel.sum::<true, _>(at, (3, 10, &js), &mut force, &law, &mut columns);
                results.push((g, flags, force, energy));
            }
        }
        assert!(results[0].1 != 0 && results[0].1 != (1 << 61) - 1, "some bonds flagged, not all");
        assert!(results[0].3 > 0.0, "the energy is summed");
        for r in &results[1..] {
            assert_eq!(r.0.map(f64::to_bits), results[0].0.map(f64::to_bits));
            assert_eq!(r.1, results[0].1);
            assert_eq!(r.3.to_bits(), results[0].3.to_bits());
            assert!(r.2.iter().zip(&results[0].2).all(|(a, b)| a.map(f64::to_bits) == b.map(f64::to_bits)));
        }
    }
}
