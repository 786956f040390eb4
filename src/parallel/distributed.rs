//! The solve of `A x = b` over MPI ranks with PETSc ([`crate::parallel::petsc`]).
//!
//! The unknowns belong to points (nodes and ghosts), `k` per point. Each point has an
//! owner rank ([`Distribution`]); PETSc wants each rank's rows contiguous, so the
//! points are renumbered rank by rank (PETSc index) and each point's `k` unknowns stay
//! together (the matrix block size, which GAMG uses with the rigid-body modes).
//!
//! [`solve`] takes the entries of the rows this rank owns, in the original
//! numbering, and does what the in-process solvers do around PETSc's KSP:
//! 1. scales the loads by a power of two and each row by `±1 / max_j |a_ij|`
//!    ([`crate::linalg::scaling`]);
//! 2. hands the rows to KSP (GMRES with the scene's preconditioner by default, right
//!    preconditioning, so the tolerance bounds the true residual);
//! 3. gathers the solution on every rank and recomputes the true relative residual
//!    `‖b − A x‖₂ / ‖b‖₂` of the equilibrated system from the rows (summed over ranks),
//!    never PETSc's estimate; a diverged KSP is reported with PETSc's converged reason.
//!
//! Every rank learns of every failure before the next collective call, so one rank's
//! error never leaves the others waiting.

use super::petsc::{self, KspDefaults, LocalRows, World};
use crate::linalg::report::{KspSettings, RankReport};
use crate::linalg::scaling::row_scale;
use crate::linalg::triplets::{compress, Entry};
use crate::linalg::{Krylov, SolveError, SolveReport, SolverKind, SolverParams};

/// Owner rank and PETSc index of every point.
#[derive(Debug, Clone)]
pub struct Distribution {
    /// This process and its world.
    pub world: World,
    /// Unknowns per point.
    pub per_point: usize,
    /// Owner rank of each point.
    owner: Vec<u32>,
    /// PETSc index of each point: rank 0's points first, each rank's in point order.
    index: Vec<usize>,
    /// Points per rank.
    counts: Vec<usize>,
}

impl Distribution {
    /// The distribution of points owned by `owner` (ranks `< world.size`).
    pub fn new(owner: Vec<u32>, per_point: usize, world: World) -> Self {
        let mut counts = vec![0usize; world.size];
        for &o in &owner {
            counts[o as usize] += 1;
        }
        let mut next: Vec<usize> = counts.iter().scan(0, |s, &c| Some(std::mem::replace(s, *s + c))).collect();
        let index = owner
            .iter()
            .map(|&o| {
                let k = next[o as usize];
                next[o as usize] += 1;
                k
            })
            .collect();
        Distribution { world, per_point, owner, index, counts }
    }

    /// Whether this rank owns point `p`.
    pub fn owns_point(&self, p: usize) -> bool {
        self.owner[p] as usize == self.world.rank
    }

    /// Whether this rank owns the row (and unknown) `row`.
    pub fn owns_row(&self, row: usize) -> bool {
        self.owns_point(row / self.per_point)
    }

    /// Points owned by each rank.
    pub fn counts(&self) -> &[usize] {
        &self.counts
    }

    /// PETSc index of unknown `u`.
    fn petsc(&self, u: usize) -> usize {
        self.index[u / self.per_point] * self.per_point + u % self.per_point
    }

    /// Number of rows (unknowns) of the whole system.
    fn rows(&self) -> usize {
        self.owner.len() * self.per_point
    }

    /// First PETSc row of this rank.
    fn first_row(&self) -> usize {
        self.counts[..self.world.rank].iter().sum::<usize>() * self.per_point
    }
}

/// The per-rank numbers `local` of every rank, in rank order.
pub fn gather_counts(local: &[f64]) -> Result<Vec<Vec<f64>>, SolveError> {
    let size = petsc::world().size;
    let all = petsc::gather_all(local, &vec![local.len(); size]).map_err(petsc_error)?;
    Ok(all.chunks(local.len().max(1)).map(<[f64]>::to_vec).collect())
}

fn petsc_error(detail: String) -> SolveError {
    SolveError::Petsc { detail }
}

/// `local`, or an error when another rank failed: a failure on any rank becomes a
/// failure on every rank, before the next collective call (one rank alone: `local`).
pub fn agree<T, E: From<SolveError>>(local: Result<T, E>) -> Result<T, E> {
    let failed_elsewhere = petsc::any_rank(local.is_err());
    match local {
        Err(e) => Err(e),
        Ok(_) if failed_elsewhere => Err(other_rank_failed().into()),
        Ok(v) => Ok(v),
    }
}

/// The error of a rank whose own work succeeded while another rank's failed.
pub fn other_rank_failed() -> SolveError {
    SolveError::Petsc { detail: "another MPI rank failed (rank 0 prints its own error; run with -n 1 to see each)".into() }
}

/// The largest `|v|` over every rank.
fn max_over_ranks(v: f64) -> Result<f64, SolveError> {
    let size = petsc::world().size;
    let all = petsc::gather_all(&[v], &vec![1; size]).map_err(petsc_error)?;
    Ok(all.iter().fold(0.0f64, |m, x| m.max(*x)))
}

/// The rows this rank owns, in PETSc's numbering, compressed (CSR, columns sorted,
/// duplicates summed), each multiplied by its scale.
struct OwnedRows {
    /// Original row of each local row.
    original: Vec<usize>,
    row_ptr: Vec<i64>,
    cols: Vec<i64>,
    vals: Vec<f64>,
    /// Row scale (`scaling::row_scale`; 1 without equilibration).
    scales: Vec<f64>,
}

/// Pack the owned rows of `entries` by a counting sort on the local row
/// ([`compress`]: two passes over the entries, no vector per row), and the checks of
/// each row: the first non-finite entry, an all-zero row (returned beside
/// the rows: every rank must reach [`agree`] before anything fails).
fn own_rows(dist: &Distribution, entries: impl Iterator<Item = Entry> + Clone, equilibrate: bool) -> (OwnedRows, Result<(), SolveError>) {
    let first = dist.first_row();
    let local_n = dist.counts[dist.world.rank] * dist.per_point;
    let mut original = vec![usize::MAX; local_n];
    for u in (0..dist.rows()).filter(|&u| dist.owns_row(u)) {
        original[dist.petsc(u) - first] = u;
    }
    let owned = entries.filter(|e| dist.owns_row(e.0)).map(|(r, c, v)| (dist.petsc(r) - first, dist.petsc(c) as i64, v));
    let (ptr, cols, mut vals) = compress(local_n, owned);
    let mut checked = Ok(());
    let mut scales = vec![1.0; local_n];
    for l in 0..local_n {
        let merged = ptr[l]..ptr[l + 1];
        if let Some(j) = merged.clone().find(|&j| !vals[j].is_finite()) {
            checked = checked.and(Err(SolveError::NotFinite { row: original[l], col: cols[j] as usize, value: vals[j] }));
        }
        let largest = vals[merged.clone()].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if largest == 0.0 {
            checked = checked.and(Err(SolveError::Singular {
                detail: format!("row {} of the matrix is entirely zero: its equation constrains nothing", original[l]),
            }));
        }
        if equilibrate && largest > 0.0 {
            let own = (first + l) as i64;
            let diagonal = merged.clone().find(|&j| cols[j] == own).map_or(0.0, |j| vals[j]);
            scales[l] = row_scale(largest, diagonal);
            vals[merged].iter_mut().for_each(|v| *v *= scales[l]);
        }
    }
    let row_ptr: Vec<i64> = ptr.into_iter().map(|p| p as i64).collect();
    (OwnedRows { original, row_ptr, cols, vals, scales }, checked)
}

/// Solve with `params.kind = Petsc` (module docs). `entries` are `(row, column,
/// value)` of the rows this rank owns (duplicates summed, other rows ignored), in the
/// original numbering; `b` the right-hand side (only owned rows read); `points` the
/// position of every point (for the rigid-body modes of GAMG). Returns the whole
/// solution on every rank.
pub fn solve(
    dist: &Distribution,
    entries: impl Iterator<Item = Entry> + Clone,
    b: &[f64],
    points: &[[f64; 2]],
    params: &SolverParams,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let SolverKind::Petsc { krylov: Krylov { preconditioner, tolerance, max_iterations }, restart, direct } = params.kind else {
        return Err(SolveError::Dimension { detail: format!("{} is not a PETSc solver", params.kind.label()) });
    };
    let k = dist.per_point;
    let n = b.len();
    let first = dist.first_row();
    let local_n = dist.counts[dist.world.rank] * k;
    let (owned, checked) = own_rows(dist, entries, params.equilibrate);
    let checked = match (0..local_n).map(|l| owned.original[l]).find(|&u| !b[u].is_finite()) {
        Some(u) => checked.and(Err(SolveError::Dimension { detail: format!("right-hand side entry {u} is not finite ({})", b[u]) })),
        None => checked,
    };
    agree(checked)?;

    let (rhs, exponent) = scaled_loads(&owned, b)?;
    let halo = halo_unknowns(&owned.cols, first as i64..(first + local_n) as i64);
    // GAMG's rigid-body modes need the positions of this rank's points.
    let coords = (preconditioner == crate::linalg::Preconditioner::Amg && !direct && k == 2).then(|| owned_positions(dist, points));
    let local = LocalRows {
        global_rows: n,
        row_ptr: &owned.row_ptr,
        cols: &owned.cols,
        vals: &owned.vals,
        rhs: &rhs,
        block_size: k,
        coords: coords.as_deref(),
    };
    let defaults = KspDefaults {
        ksp_type: "gmres",
        pc_type: if direct { "lu" } else { preconditioner.petsc_name().unwrap_or("gamg") },
        factor_package: if direct { "mumps" } else { "" },
        rtol: tolerance,
        max_it: max_iterations,
        restart,
    };
    let out = petsc::solve(&local, &defaults).map_err(petsc_error)?;

    // The whole solution on every rank, in PETSc order, then in the original one.
    let counts: Vec<usize> = dist.counts.iter().map(|c| c * k).collect();
    let x_petsc = petsc::gather_all(&out.x, &counts).map_err(petsc_error)?;
    let sums = residual_sums(&owned, &rhs, &x_petsc)?;
    let relative = |r2: f64, b2: f64| if b2 > 0.0 { (r2 / b2).sqrt() } else { r2.sqrt() };
    let relative_residual = relative(sums[0], sums[1]);
    let method = format!("petsc:{}+{}", out.ksp_type, out.pc_type);
    check_converged(&out, relative_residual, &method)?;
    let mut x = vec![0.0; n];
    for (u, xu) in x.iter_mut().enumerate() {
        *xu = x_petsc[dist.petsc(u)] * power_of_two(exponent);
    }
    if let Some(u) = x.iter().position(|v| !v.is_finite()) {
        return Err(SolveError::Overflow { detail: format!("unknown {u} is beyond the double range: rescale the loads") });
    }
    let largest = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let report = SolveReport {
        method,
        choice: None,
        iterations: out.iterations,
        relative_residual,
        original_relative_residual: relative(sums[2], sums[3]),
        setup_seconds: out.setup_seconds,
        solve_seconds: out.solve_seconds,
        equilibrated: params.equilibrate,
        preconditioner_nonzeros: None,
        restarts: 0,
        subnormal_unknowns: x.iter().filter(|v| v.is_subnormal() && v.abs() > 1e-12 * largest).count(),
        condition_estimate: None,
        // PETSc's KSP holds the preconditioner; its error is not estimated here.
        solver_error: None,
        ranks: Some(rank_report(dist.world.size, local_n, owned.cols.len(), halo)?),
        petsc: Some(KspSettings {
            ksp_type: out.ksp_type.clone(),
            pc_type: out.pc_type.clone(),
            rtol: out.rtol,
            max_it: out.max_it,
            converged_reason: out.reason_name.clone(),
        }),
    };
    Ok((x, report))
}

/// Every rank's rows, entries and halo unknowns, gathered on every rank (the stage
/// seconds are filled in by the model at the end of the run).
fn rank_report(ranks: usize, rows: usize, nonzeros: usize, halo: usize) -> Result<RankReport, SolveError> {
    let per_rank = gather_counts(&[rows as f64, nonzeros as f64, halo as f64])?;
    let column = |j: usize| per_rank.iter().map(|r| r[j] as usize).collect();
    Ok(RankReport { ranks, rows: column(0), nonzeros: column(1), halo_unknowns: column(2), stage_seconds: Vec::new() })
}

/// `2^e` without overflow in the intermediate (two factors).
fn power_of_two(e: i32) -> f64 {
    2f64.powi(e / 2) * 2f64.powi(e - e / 2)
}

/// This rank's loads scaled by a power of two `2^-e` that brings the largest over the
/// ranks into `[1, 2)` (exact), as in `linalg::solve`, and by the row scales; with `e`.
fn scaled_loads(owned: &OwnedRows, b: &[f64]) -> Result<(Vec<f64>, i32), SolveError> {
    let b_max = max_over_ranks(owned.original.iter().fold(0.0f64, |m, &u| m.max(b[u].abs())))?;
    let exponent = if b_max > 0.0 { b_max.log2().floor() as i32 } else { 0 };
    let rhs = owned.original.iter().zip(&owned.scales).map(|(&u, s)| b[u] * power_of_two(-exponent) * s).collect();
    Ok((rhs, exponent))
}

/// The positions of this rank's points, in PETSc order.
fn owned_positions(dist: &Distribution, points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let first = dist.first_row() / dist.per_point;
    let mut c = vec![[0.0; 2]; dist.counts[dist.world.rank]];
    for (p, point) in points.iter().enumerate().filter(|(p, _)| dist.owns_point(*p)) {
        c[dist.index[p] - first] = *point;
    }
    c
}

/// The distinct unknowns outside `own` (this rank's rows) that the columns `cols` read.
fn halo_unknowns(cols: &[i64], own: std::ops::Range<i64>) -> usize {
    let mut outside: Vec<i64> = cols.iter().copied().filter(|c| !own.contains(c)).collect();
    outside.sort_unstable();
    outside.dedup();
    outside.len()
}

/// `[‖r‖², ‖b‖²]` of the solved (row-scaled) system and the same of the original
/// rows, `r = b - A x` over this rank's rows, summed over the ranks.
fn residual_sums(owned: &OwnedRows, rhs: &[f64], x: &[f64]) -> Result<[f64; 4], SolveError> {
    let mut sums = [0.0; 4];
    for (l, (&b, &scale)) in rhs.iter().zip(&owned.scales).enumerate() {
        let range = owned.row_ptr[l] as usize..owned.row_ptr[l + 1] as usize;
        let ax: f64 = owned.cols[range.clone()].iter().zip(&owned.vals[range]).map(|(&c, v)| v * x[c as usize]).sum();
        let r = b - ax;
        sums[0] += r * r;
        sums[1] += b * b;
        sums[2] += (r / scale).powi(2);
        sums[3] += (b / scale).powi(2);
    }
    petsc::sum_over_ranks(&mut sums).map_err(petsc_error)?;
    Ok(sums)
}

/// Refuses a KSP that diverged, or whose true relative residual is above 10 x the
/// rtol it reported reaching (NaN included).
fn check_converged(out: &petsc::KspOutcome, relative_residual: f64, method: &str) -> Result<(), SolveError> {
    let within = relative_residual <= 10.0 * out.rtol; // false for NaN
    if out.reason >= 0 && within {
        return Ok(());
    }
    let limit = if out.reason < 0 {
        format!("PETSc's converged reason {} ({})", out.reason_name, out.reason)
    } else {
        format!("PETSc reported {} but the true residual is above 10 x its rtol {:e}", out.reason_name, out.rtol)
    };
    let hint = "try PETSc's distributed LU (-pc_type lu -pc_factor_mat_solver_type mumps), another -pc_type or a larger -ksp_max_it";
    Err(SolveError::NoConvergence {
        hint,
        iterations: out.iterations,
        restarts: 0,
        limit,
        relative_residual,
        method: method.to_string(),
        tolerance: out.rtol,
    })
}

/// Every rank's `(stage, seconds)`, in rank order (collective; each rank ran the same
/// stages, a stage another rank lacks reads 0).
pub fn stage_seconds_per_rank(local: &[(String, f64)]) -> Result<Vec<Vec<(String, f64)>>, SolveError> {
    let seconds: Vec<f64> = local.iter().map(|s| s.1).collect();
    let longest = gather_counts(&[seconds.len() as f64])?.iter().fold(0usize, |m, c| m.max(c[0] as usize));
    let mut padded = seconds;
    padded.resize(longest, 0.0);
    let all = gather_counts(&padded)?;
    Ok(all.iter().map(|r| local.iter().zip(r).map(|((name, _), &t)| (name.clone(), t)).collect()).collect())
}
