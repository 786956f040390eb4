//! Smoothed-aggregation algebraic multigrid (SA-AMG) for the nonsymmetric collocation
//! and peridynamic systems, used as one V-cycle per preconditioner application.
//!
//! Setup, level by level (Vaněk, Mandel, Brezina, *Computing* 56 (1996) 179–196; the
//! nonsymmetric restriction of Sala & Tuminaro, *SIAM J. Sci. Comput.* 31 (2008)
//! 143–166, as pyamg's `symmetry = "nonsymmetric"` does it):
//! 1. node graph of strong blocks and aggregates ([`super::aggregation`]);
//! 2. tentative prolongator `T` from the near-null space `B`: the rigid-body modes
//!    `(1, 0)`, `(0, 1)`, `(−y, x)` at each node's position, which every Navier and
//!    peridynamic row annihilates except the Dirichlet rows;
//! 3. smoothed prolongator `P = (I − ω D⁻¹ A) T` and restriction
//!    `R = Tᵀ (I − ω A D⁻¹)` (the same smoothing applied with `Aᵀ`), `D` the 2x2 (3x3
//!    on coarse levels) diagonal blocks, `ω = 4 / (3 ρ(D⁻¹ A))`;
//! 4. coarse operator `A_c = R A P`, coarse near-null space from the factorisation.
//!
//! The cycle smooths with block Gauss–Seidel, a forward and a backward sweep before
//! and after the coarse correction; the coarsest level is solved by dense LU.
//!
//! Why written here: no Rust crate offers aggregation with a vector near-null space
//! and nodal blocks. `russell_sparse` 5.1 ships a scalar AMG (AMGCL port) without a
//! near-null space; on our cantilever systems it broke down or diverged from about
//! 8e4 unknowns. pyamg on the exported systems (`../shared/docs/solvers.md`) showed
//! that this configuration gives flat iteration counts on grids (27–34 over 23x in
//! size), and which alternatives fail.

use super::aggregation::{aggregate, strength_graph, tentative, Blocks};
use super::blocks::Transfer;
use super::csr::{product, to_csr, Csr};
pub use super::layout::NodeLayout;
pub use super::level_operator::Finest;
use super::level_operator::LevelOperator;
use super::near_null::{left_near_null, rigid_body_modes, LEFT_NULL_ITERATIONS};
use super::smoother::{inverse_diagonal_blocks, Sweep};
use super::SparseMatrix;
use super::orthogonal::orthogonalise;
use super::{spgemm, vector_state};
use nalgebra::DMatrix;

/// Settings of the hierarchy.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AmgParams {
    /// Strength threshold θ of [`strength_graph`] on the finest level (0: every
    /// coupling is strong).
    pub strength: f64,
    /// θ on the coarser levels, whose operators couple each aggregate with many others:
    /// with θ = 0 there the second coarsening took about 25 nodes per aggregate and the
    /// third level was too coarse; 0.05 lowered the iterations on the cantilever, Lame
    /// and Kirsch (docs/notebook/2026-11-25-multigrid-symmetry-edges.md, "A strength
    /// threshold on the coarse levels").
    pub coarse_strength: f64,
    /// Stop coarsening at this many unknowns and solve that level directly.
    pub max_coarse: usize,
    /// Levels at most.
    pub max_levels: usize,
}

impl Default for AmgParams {
    fn default() -> Self {
        AmgParams { strength: 0.0, coarse_strength: 0.05, max_coarse: 400, max_levels: 12 }
    }
}

/// Cycles of [`Amg::cycle_growth`]'s power iteration (the L bracket's growth of 1e6
/// per cycle shows from the first; the column's 0.92 needs two to settle).
const GROWTH_CYCLES: usize = 3;

/// Seed of [`Amg::cycle_growth`]'s start vector.
const GROWTH_SEED: u64 = 12;

/// One level: its operator, the inverses of its diagonal blocks, and the transfers to
/// the next coarser level.
#[derive(Debug)]
struct Level {
    a: LevelOperator,
    blocks: Blocks,
    /// Pseudo-inverse of each diagonal block, row-major, `block²` per node.
    inv_diag: Vec<f64>,
    /// The transfers in single precision: a fixed linear map is all the cycle needs of
    /// them, and they are the largest part of the hierarchy
    /// (docs/notebook/round2-target-error.md, "Rows assembled in node order,
    /// single-precision transfers"); stored by aggregate ([`Transfer`]).
    p: Transfer,
    r: Transfer,
}

/// The coarsest level, factored.
#[derive(Debug)]
struct Coarsest {
    lu: faer::linalg::solvers::PartialPivLu<f64>,
    n: usize,
}

/// A smoothed-aggregation hierarchy; [`Amg::solve_into`] is one V-cycle from a zero guess.
#[derive(Debug)]
pub struct Amg {
    levels: Vec<Level>,
    coarsest: Coarsest,
    /// The operator itself when the hierarchy has one level (it was small enough to
    /// factor directly) and it is the system ([`Finest::System`]).
    single: Option<Csr>,
    /// Unknowns per level, finest first (the coarsest included).
    sizes: Vec<usize>,
    /// Stored entries of all operators and transfers.
    nonzeros: usize,
    /// `Σ nnz(A_l) / nnz(A_0)`.
    operator_complexity: f64,
    /// The cycle's vectors.
    work: std::sync::Mutex<Workspace>,
}

/// The block-diagonal matrix of `inv_diag`.
fn block_diagonal(inv_diag: &[f64], blocks: Blocks) -> Csr {
    let b = blocks.block;
    let n = blocks.nodes * b;
    let offsets: Vec<usize> = (0..=n).map(|r| r * b).collect();
    let cols: Vec<u32> = (0..n).flat_map(|r| (0..b).map(move |c| ((r / b) * b + c) as u32)).collect();
    Csr::from_parts(n, n, offsets, cols, inv_diag.to_vec())
}

/// Spectral radius of `M = D⁻¹ A` estimated from the Ritz values of a 15-step Arnoldi
/// process, as many as pyamg's `approximate_spectral_radius` takes (power iteration
/// underestimates it on nonsymmetric `M`, and `ω` too large makes the smoothed
/// prolongator amplify instead of smooth). 15 steps gave nearly the ρ of 20 and the
/// same iterations (docs/notebook/round2-target-error.md, "A cheaper multigrid
/// setup"); the orthogonalisation grows with the square of the steps.
fn spectral_radius(a: &Csr, inv_diag: &Csr) -> f64 {
    let n = a.nrows();
    let steps = 15.min(n);
    // A fixed, non-smooth start vector: deterministic runs.
    let mut v: Vec<Vec<f64>> = vec![(0..n).map(|i| 1.0 + ((i * 7919) % 13) as f64 / 13.0).collect()];
    let norm = super::norm2(&v[0]);
    v[0].iter_mut().for_each(|x| *x /= norm);
    let mut h = DMatrix::<f64>::zeros(steps + 1, steps);
    let mut tmp = vec![0.0; n];
    let mut m = 0;
    for j in 0..steps {
        product(a, &v[j], &mut tmp);
        let mut w = vec![0.0; n];
        product(inv_diag, &tmp, &mut w);
        let (projections, norm) = orthogonalise(&v, &mut w);
        for (i, d) in projections.into_iter().enumerate() {
            h[(i, j)] = d;
        }
        h[(j + 1, j)] = norm;
        m = j + 1;
        if norm <= 1e-12 * h.column(j).norm() {
            break;
        }
        w.iter_mut().for_each(|x| *x /= norm);
        v.push(w);
    }
    let square = h.view((0, 0), (m, m)).clone_owned();
    square.complex_eigenvalues().iter().map(|z| z.norm()).fold(0.0, f64::max)
}

impl Amg {
    /// The hierarchy of `a` (the system as solved, row-equilibrated) with the rigid-body
    /// modes of `layout` as near-null space; the Krylov method keeps `a` itself, so the
    /// hierarchy keeps only the single-precision copy its cycle applies.
    pub fn build(a: &SparseMatrix, layout: Option<NodeLayout>, params: AmgParams) -> Result<Self, super::SolveError> {
        Ok(Self::build_from_rows(to_csr(a), layout, params, Finest::PreconditionerOnly))
    }

    /// [`Amg::build`] from the operator in compressed rows, which the hierarchy keeps
    /// as its finest level as `keep` says.
    pub fn build_from_rows(a: Csr, layout: Option<NodeLayout>, params: AmgParams, keep: Finest) -> Self {
        let n = a.nrows();
        let (mut null, k) = rigid_body_modes(n, layout);
        // The left near-null space of the finest level, relaxed from the rigid-body
        // modes (`left_near_null`); on coarser levels its image under the tentative
        // factorisation, as for `null`.
        let mut left = Vec::new();
        let block = layout.map(|l| l.per_node).filter(|&b| b >= 2 && n.is_multiple_of(b)).unwrap_or(1);
        let mut current = a;
        let mut blocks = Blocks { block, nodes: n / block };
        let mut levels = Vec::new();
        let mut sizes = vec![n];
        while current.nrows() > params.max_coarse && levels.len() + 1 < params.max_levels {
            let inv_diag = inverse_diagonal_blocks(&current, blocks);
            let theta = if levels.is_empty() { params.strength } else { params.coarse_strength };
            let graph = strength_graph(&current, blocks, theta);
            let (agg, count) = aggregate(&graph);
            // No coarsening (every node its own aggregate) would loop forever.
            if count * k >= current.nrows() {
                break;
            }
            let d = block_diagonal(&inv_diag, blocks);
            // P = T − ω (D⁻¹ A) T and R = Tᵀ − ω (Tᵀ A) D⁻¹, each formed row by row
            // in single precision (`spgemm::smoothed`): what the cycle applies and what
            // the coarse operator is formed with. The finest level's left near-null
            // space (serial sweeps) is grown on one thread while `P` is formed.
            let grow_left = || levels.is_empty().then(|| left_near_null(&current, blocks, &inv_diag, &null, k, LEFT_NULL_ITERATIONS));
            let (grown, (p, coarse_null, omega)) = rayon::join(grow_left, || {
                let (t, coarse_null) = tentative(&null, k, blocks, &agg, count);
                let rho = spectral_radius(&current, &d).max(f64::MIN_POSITIVE);
                let omega = 4.0 / (3.0 * rho);
                (spgemm::smoothed(&t, omega, &d, &current, &t), coarse_null, omega)
            });
            if let Some(grown) = grown {
                left = grown;
            }
            let (t_left, coarse_left) = tentative(&left, k, blocks, &agg, count);
            let r = {
                let tt = t_left.transpose();
                drop(t_left);
                spgemm::smoothed(&tt, omega, &tt, &current, &d)
            };
            drop(d);
            let coarse = spgemm::triple_product(&r, &current, &p);
            let (p, r) = (Transfer::new(p, (1, k)), Transfer::new(r, (k, 1)));
            let a = LevelOperator::new(current, if levels.is_empty() { keep } else { Finest::PreconditionerOnly }, blocks);
            levels.push(Level { a, blocks, inv_diag, p, r });
            sizes.push(coarse.nrows());
            current = coarse;
            null = coarse_null;
            left = coarse_left;
            blocks = Blocks { block: k, nodes: count };
        }
        let coarsest = Coarsest::factor(&current);
        let nonzeros = levels.iter().map(|l| l.a.nnz() + l.p.nnz() + l.r.nnz()).sum::<usize>() + current.nnz();
        let fine = levels.first().map_or(current.nnz(), |l| l.a.nnz()) as f64;
        let operator_complexity = (levels.iter().map(|l| l.a.nnz()).sum::<usize>() + current.nnz()) as f64 / fine;
        let single = (levels.is_empty() && keep == Finest::System).then_some(current);
        let work = Workspace { input: Vec::new(), levels: levels.iter().map(|_| LevelWork::default()).collect() };
        Amg { levels, coarsest, single, sizes, nonzeros, operator_complexity, work: std::sync::Mutex::new(work) }
    }

    /// Unknowns per level, finest first.
    pub fn sizes(&self) -> &[usize] {
        &self.sizes
    }

    /// Stored entries of operators and transfers over all levels.
    pub fn nonzeros(&self) -> usize {
        self.nonzeros
    }

    /// `Σ nnz(A_l) / nnz(A_0)`: memory and work of a cycle relative to one product.
    pub fn operator_complexity(&self) -> f64 {
        self.operator_complexity
    }

    /// The finest operator (the system as solved) in compressed rows, kept when the
    /// hierarchy was built with [`Finest::System`].
    pub fn fine_operator(&self) -> Option<&Csr> {
        match self.levels.first() {
            Some(level) => level.a.system_rows(),
            None => self.single.as_ref(),
        }
    }

    /// The finest operator ([`Amg::fine_operator`]), the rest of the hierarchy dropped
    /// (a solver that gives up on the multigrid frees its memory before it tries
    /// another method).
    pub fn into_fine_operator(self) -> Option<Csr> {
        match self.levels.into_iter().next() {
            Some(level) => level.a.into_system_rows(),
            None => self.single,
        }
    }

    /// Unknowns of the finest level.
    pub fn dim(&self) -> usize {
        self.sizes[0]
    }

    /// How much one V-cycle, as the stationary iteration `e ← e − M⁻¹ A e` on the
    /// finest operator, amplifies an error: `‖e₃‖ / ‖e₂‖` after [`GROWTH_CYCLES`]
    /// cycles from a fixed pseudo-random `e₀` (a power iteration: the ratio approaches
    /// the spectral radius of `I − M⁻¹ A`). Below 1 the cycle converges by itself;
    /// far above it the smoother or the coarse correction diverges. `None` for a
    /// hierarchy of one level (a direct solve). Costs a product and a cycle per step:
    /// computed to explain a failure, not on every solve.
    pub fn cycle_growth(&self) -> Option<f64> {
        let level = self.levels.first()?;
        let n = self.dim();
        // A fixed seed: deterministic, and no smoothness for a structured mode to hide behind.
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(GROWTH_SEED);
        let mut e: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let (mut ae, mut z) = (vec![0.0; n], vec![0.0; n]);
        let mut growth = 0.0;
        for _ in 0..GROWTH_CYCLES {
            let before = super::norm2(&e);
            if !(before > 0.0 && before.is_finite()) {
                break;
            }
            e.iter_mut().for_each(|v| *v /= before);
            level.a.product(&e, &mut ae);
            self.solve_into(&ae, &mut z);
            e.iter_mut().zip(&z).for_each(|(e, z)| *e -= z);
            growth = super::norm2(&e);
        }
        Some(if growth.is_finite() { growth } else { f64::INFINITY })
    }

    /// `x ← M⁻¹ x`: one V-cycle for `A z = x` from `z = 0`.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        // One caller at a time (GMRES applies the preconditioner from one thread); a
        // panic elsewhere leaves buffers that are overwritten before they are read.
        let mut work = self.work.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        let Workspace { input, levels } = &mut *work;
        input.resize(x.len(), 0.0);
        input.copy_from_slice(x);
        self.cycle(0, input, x, levels);
    }

    /// `z = M⁻¹ f`: one V-cycle for `A z = f` from `z = 0` ([`Amg::solve_in_place`]
    /// without the copy of `f`).
    pub fn solve_into(&self, f: &[f64], z: &mut [f64]) {
        let mut work = self.work.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        self.cycle(0, f, z, &mut work.levels);
    }

    fn cycle(&self, l: usize, f: &[f64], z: &mut [f64], work: &mut [LevelWork]) {
        let (Some(level), Some((own, coarser))) = (self.levels.get(l), work.split_first_mut()) else {
            self.coarsest.solve(f, z);
            return;
        };
        let LevelWork { residual: r, copies, coarse_rhs: fc, coarse_correction: zc } = own;
        r.resize(f.len(), 0.0);
        fc.resize(level.r.nrows(), 0.0);
        zc.resize(level.r.nrows(), 0.0);
        z.fill(0.0);
        level.gauss_seidel(f, z, Sweep::ForwardFromZero, copies);
        level.gauss_seidel(f, z, Sweep::Backward, copies);
        level.a.product(z, r);
        r.iter_mut().zip(f).for_each(|(r, f)| *r = f - *r);
        level.r.product(r, fc);
        self.cycle(l + 1, fc, zc, coarser);
        level.p.product(zc, r);
        z.iter_mut().zip(r.iter()).for_each(|(z, c)| *z += c);
        level.gauss_seidel(f, z, Sweep::Forward, copies);
        level.gauss_seidel(f, z, Sweep::Backward, copies);
    }
}

impl Level {
    /// One block Gauss–Seidel sweep of this level ([`gauss_seidel`]).
    fn gauss_seidel(&self, f: &[f64], z: &mut [f64], direction: Sweep, copies: &mut Vec<Vec<f64>>) {
        self.a.gauss_seidel((self.blocks, &self.inv_diag), f, z, direction, copies);
    }
}

/// The vectors one V-cycle works in, kept between applications: allocated per cycle,
/// they were fresh pages to fault in and zero at every GMRES iteration.
#[derive(Debug, Default)]
struct Workspace {
    /// The right-hand side of the cycle (the vector it overwrites).
    input: Vec<f64>,
    /// One per level with a coarser one.
    levels: Vec<LevelWork>,
}

/// The vectors of one level of the cycle.
#[derive(Debug, Default)]
struct LevelWork {
    /// `f − A z`, then the prolongated correction.
    residual: Vec<f64>,
    /// The private copies of the iterate of a parallel Gauss–Seidel sweep ([`gauss_seidel`]).
    copies: Vec<Vec<f64>>,
    /// `R (f − A z)`.
    coarse_rhs: Vec<f64>,
    /// The coarser level's solution.
    coarse_correction: Vec<f64>,
}

impl Coarsest {
    /// Dense LU of the coarsest operator; unknowns whose row and column are both empty
    /// (dependent near-null vectors) get a unit diagonal, which leaves them zero.
    fn factor(a: &Csr) -> Self {
        let n = a.nrows();
        let mut dense = faer::Mat::<f64>::zeros(n, n);
        let mut used = vec![false; n];
        for r in 0..n {
            let row = a.row(r);
            for (&c, &v) in row.col_indices().iter().zip(row.values()) {
                let c = c as usize;
                dense[(r, c)] += v;
                if v != 0.0 {
                    used[r] = true;
                    used[c] = true;
                }
            }
        }
        for (i, u) in used.iter().enumerate() {
            if !u {
                dense[(i, i)] = 1.0;
            }
        }
        let lu = dense.partial_piv_lu();
        vector_state::clear_upper_halves_everywhere();
        Coarsest { lu, n }
    }

    fn solve(&self, f: &[f64], z: &mut [f64]) {
        use faer::linalg::solvers::Solve;
        let rhs = faer::MatRef::from_column_major_slice(f, self.n, 1);
        let x = self.lu.solve(rhs);
        vector_state::clear_upper_halves();
        for (i, zi) in z.iter_mut().enumerate() {
            *zi = if x[(i, 0)].is_finite() { x[(i, 0)] } else { 0.0 };
        }
    }
}

#[cfg(test)]
#[path = "amg_tests.rs"]
mod tests;
