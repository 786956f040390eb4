//! Command-line interface (clap derive).

use clap::{Parser, Subcommand};
use std::path::PathBuf;

/// Meshless (MLSM) solver for 2D linear elasticity.
#[derive(Debug, Parser)]
#[command(name = "mlsm", version, about, long_about = None)]
pub struct Cli {
    /// Print nothing but errors.
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// A positive finite number (a spacing, horizon or ratio); negative numbers reach this
/// check instead of clap's "unexpected argument" (`allow_negative_numbers`).
fn positive(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        Ok(v) => Err(format!("must be a positive number, got {v}")),
        Err(_) => Err(format!("\"{text}\" is not a number")),
    }
}

/// A time budget: seconds (`120`), or with a unit (`90s`, `2m`, `1h 30m`); positive.
fn budget(text: &str) -> Result<std::time::Duration, String> {
    /// A year: longer budgets are typos (and a deadline past the clock's range panics).
    const LONGEST: f64 = 3.2e7;
    let t = text.trim();
    let d = match t.parse::<f64>() {
        Ok(s) if s.is_finite() && s > 0.0 => std::time::Duration::from_secs_f64(s.min(2.0 * LONGEST)),
        Ok(s) => return Err(format!("must be a positive number of seconds, got {s}")),
        Err(_) => humantime::parse_duration(t).map_err(|e| format!("\"{t}\" is not a duration ({e}); write e.g. 120, 90s, 2m"))?,
    };
    if d.is_zero() {
        return Err("must be longer than zero".into());
    }
    if d.as_secs_f64() > LONGEST {
        return Err(format!("{t} is longer than a year ({LONGEST:.1e} s)"));
    }
    Ok(d)
}

/// Model selector of `run`.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum ModelArg {
    /// The Navier equation by MLSM.
    Navier,
    /// Linear bond-based peridynamics.
    Peridynamics,
}

/// The norm of `run --target-error` (the names of `summary.json`).
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum TargetNormArg {
    /// Relative max-norm error of the displacement.
    #[value(name = "e_inf_u")]
    EInfU,
    /// Relative max-norm error of the stress.
    #[value(name = "e_inf_sigma")]
    EInfSigma,
    /// Relative L2 error of the displacement.
    #[value(name = "rel_l2_u")]
    RelL2U,
    /// Relative L2 error of the stress.
    #[value(name = "rel_l2_sigma")]
    RelL2Sigma,
}

/// How `run --target-error` refines.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum RefinementArg {
    /// Uniform where the solution is smooth (no singular corner), local where it is not.
    Auto,
    /// Graded refinement where the per-node estimate is large.
    Local,
    /// The whole spacing function scaled by one factor.
    Uniform,
}

/// Which degree `run --target-error` solves with.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum TargetDegreeArg {
    /// The scene's, raised to 6 for RBF-FD scenes without singular corners and targets of 1e-3 or less.
    Auto,
    /// The scene's own.
    Scene,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Solve a scene and write solution.vtu and summary.json.
    Run {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Output folder (default: output/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override the scene's node spacing (m), e.g. for timing studies.
        #[arg(long, allow_negative_numbers = true, value_parser = positive)]
        spacing: Option<f64>,
        /// Model to solve (default: the scene's `model`, else navier).
        #[arg(long, value_enum)]
        model: Option<ModelArg>,
        /// Override the peridynamic horizon delta (m); h = delta / m.
        #[arg(long, allow_negative_numbers = true, value_parser = positive)]
        horizon: Option<f64>,
        /// Exit with code 4 when the run ends with warnings (results are still written).
        #[arg(long)]
        strict: bool,
        /// Approximation and spacing by rule: fast, balanced or accurate (replaces the
        /// scene's `preset`, [nodes] spacing and [approximation] basis, degree, support).
        #[arg(long, value_name = "NAME")]
        preset: Option<String>,
        /// Allow an explicit dynamic run of more than 1e8 time steps.
        #[arg(long)]
        allow_long: bool,
        /// Also write the assembled system A x = b of a static Navier run into this folder
        /// (MatrixMarket and PETSc binary, with the unknowns' nodes and positions).
        #[arg(long, value_name = "DIR")]
        export_system: Option<PathBuf>,
        /// Refine until the estimated relative error (of --target-norm) is at most E:
        /// solve, estimate, refine where the per-node estimate is large, repeat.
        #[arg(long, value_name = "E", allow_negative_numbers = true, value_parser = positive)]
        target_error: Option<f64>,
        /// The norm --target-error is set on.
        #[arg(long, value_enum, default_value = "e_inf_u", requires = "target_error")]
        target_norm: TargetNormArg,
        /// How --target-error refines: auto (uniform where the solution is smooth, local
        /// at singular corners), local (graded where the estimate is large) or uniform
        /// (the whole spacing scaled; grids are always refined uniformly).
        #[arg(long, value_enum, default_value = "auto", requires = "target_error")]
        refinement: RefinementArg,
        /// The degree --target-error solves with: auto (RBF-FD raised to degree 6 where
        /// the solution is smooth and the target 1e-3 or less) or scene (the scene's).
        #[arg(long, value_enum, default_value = "auto", requires = "target_error")]
        target_degree: TargetDegreeArg,
        /// Time budget of --target-error: seconds, or 90s, 2m, 1h (default: no limit).
        #[arg(long, allow_negative_numbers = true, value_parser = budget, requires = "target_error")]
        budget: Option<std::time::Duration>,
        /// PETSc options, after `--`, passed to PETSc unchanged (solver.kind = "petsc"),
        /// e.g. `-- -ksp_type bcgs -pc_type hypre -ksp_monitor`.
        #[arg(last = true, allow_hyphen_values = true, value_name = "PETSC_OPTIONS")]
        petsc_options: Vec<String>,
    },
    /// Print every option word a scene file may use, with its default and meaning (Markdown).
    Options,
    /// Validate a scene file without solving it.
    Check {
        /// Scene file (TOML).
        scene: PathBuf,
    },
    /// Solve at K halvings of the spacing; print and write errors (exact where the scene has
    /// one, estimated always), differences between levels, observed orders, and the probes
    /// extrapolated with an error bar.
    Convergence {
        /// Scene file (TOML) of a static problem (errors where it has an [exact] solution, estimates, level differences and extrapolated probes always).
        scene: PathBuf,
        /// Number of halvings of the spacing (K + 1 runs).
        #[arg(long, default_value_t = 3)]
        levels: usize,
        /// Output folder (default: output/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Sweep spacing, basis and degree, stencil and solver within a time budget; write
    /// the runs, the Pareto front of seconds against error (CSV, JSON, SVG, PNG) and the
    /// cheapest configuration per accuracy decade.
    Tradeoff {
        /// Scene file (TOML) of a static Navier problem.
        scene: PathBuf,
        /// Time budget for the whole sweep: seconds, or 90s, 2m, 1h.
        #[arg(long, default_value = "120", allow_negative_numbers = true, value_parser = budget)]
        budget: std::time::Duration,
        /// Output folder (default: output/<scene name>/tradeoff).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Peridynamics at a sequence of horizons against the local (Navier) solution:
    /// difference norms on the interior region and the whole plate, observed orders in delta.
    Compare {
        /// Scene file (TOML) with a [peridynamics] table.
        scene: PathBuf,
        /// Ratio m = delta / h (default: the scene's).
        #[arg(long, allow_negative_numbers = true, value_parser = positive)]
        m: Option<f64>,
        /// Horizons, comma-separated, each once (default: the scene's horizon and --levels halvings).
        // A list that starts with a minus (`-0.1,0.05`) is not one number, which is all
        // `allow_negative_numbers` takes: hyphen values reach `positive`, which names
        // --deltas in its refusal.
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true, value_parser = positive)]
        deltas: Option<Vec<f64>>,
        /// Halvings of the scene's horizon when --deltas is not given.
        #[arg(long, default_value_t = 3)]
        levels: usize,
        /// Quadrature rules, comma-separated (default: the scene's), e.g. ac,full-area,partial-area.
        #[arg(long, value_delimiter = ',')]
        quadratures: Option<Vec<String>>,
        /// Node spacing of the MLSM reference (default: the scene's; unused when the scene has an [exact] solution).
        #[arg(long, allow_negative_numbers = true, value_parser = positive)]
        reference_spacing: Option<f64>,
        /// Output folder (default: output/<scene name>/compare).
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

/// The command line with a negative number in exponent form after a long option
/// joined to it (`--spacing -1e-3` -> `--spacing=-1e-3`): clap's negative-number rule
/// knows `-1` and `-0.5` but reads `-1e-3` as short flags, and answers with a wrong tip
/// instead of the option's own message.
pub fn joined_negative_values<I: IntoIterator<Item = std::ffi::OsString>>(args: I) -> Vec<std::ffi::OsString> {
    let mut out: Vec<std::ffi::OsString> = Vec::new();
    let mut args = args.into_iter();
    for arg in args.by_ref() {
        if arg == "--" {
            // What follows `--` belongs to PETSc, untouched.
            out.push(arg);
            break;
        }
        let negative_number = arg.to_str().is_some_and(|a| a.starts_with('-') && a.parse::<f64>().is_ok());
        match out.last_mut() {
            Some(option) if negative_number && option.to_str().is_some_and(|o| o.starts_with("--") && o.len() > 2 && !o.contains('=')) => {
                option.push("=");
                option.push(&arg);
            }
            _ => out.push(arg),
        }
    }
    out.extend(args);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn negative_exponent_values_are_joined_to_their_option() {
        let args = |v: &[&str]| v.iter().map(std::ffi::OsString::from).collect::<Vec<_>>();
        assert_eq!(
            joined_negative_values(args(&["mlsm", "run", "s.toml", "--spacing", "-1e-3", "--out", "o"])),
            args(&["mlsm", "run", "s.toml", "--spacing=-1e-3", "--out", "o"])
        );
        // Not a number, or not after a long option: left alone.
        assert_eq!(joined_negative_values(args(&["mlsm", "-q", "-1e-3", "--out", "-x"])), args(&["mlsm", "-q", "-1e-3", "--out", "-x"]));
        // After `--`: PETSc's options, untouched.
        let petsc = args(&["mlsm", "run", "s.toml", "--", "--x", "-1e-3"]);
        assert_eq!(joined_negative_values(petsc.clone()), petsc);
    }
}
