//! Raw mirror of the scene file (TOML). Every table denies unknown keys; every
//! semantic check happens in `validate`, which turns a [`SceneSpec`] into a
//! [`super::Problem`].

use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

/// A whole scene file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// Scene name (default: the file stem); names the output folder.
    pub name: Option<String>,
    /// `fast`, `balanced` or `accurate`: approximation and spacing by rule.
    pub preset: Option<String>,
    /// Free text shown in the summary.
    pub description: Option<String>,
    /// The solid.
    pub domain: DomainSpec,
    /// Node generation.
    pub nodes: NodesSpec,
    /// Local approximation (defaults: monomials of degree 2, Gaussian weight).
    #[serde(default)]
    pub approximation: ApproximationSpec,
    /// Elastic constants and planar model.
    pub material: MaterialSpec,
    /// Named constants of the expressions: a number, or a formula of other constants.
    pub constants: Option<std::collections::BTreeMap<String, NumberOrFormula>>,
    /// Body force `[fx, fy]` (N/m^3; numbers or formulas in x, y) or `"exact"`.
    pub body_force: Option<VectorOrExact>,
    /// One condition per boundary part.
    #[serde(default)]
    pub boundary: Vec<BoundarySpec>,
    /// Linear solver.
    #[serde(default)]
    pub solver: SolverSpec,
    /// Requested output fields.
    #[serde(default)]
    pub output: OutputSpec,
    /// Closed-form solution to compare with (and to take boundary values from).
    pub exact: Option<ExactSpec>,
    /// Which model `mlsm run` solves: `navier` (default) or `peridynamics`.
    pub model: Option<String>,
    /// Peridynamic discretisation of the same plate.
    pub peridynamics: Option<PeridynamicsSpec>,
    /// Time-dependent run (explicit integration from initial conditions).
    pub dynamics: Option<DynamicsSpec>,
    /// Error estimate of the Navier model.
    #[serde(default)]
    pub estimate: EstimateSpec,
    /// Point values to report (`[[probe]]`).
    #[serde(default)]
    pub probe: Vec<ProbeSpec>,
}

/// `[[probe]]`: one named point value.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProbeSpec {
    /// Name (letters, digits, `_`, `-`; unique).
    pub name: Option<String>,
    /// The point `[x, y]`, on or inside the solid.
    pub at: Option<PointSpec>,
    /// `ux`, `uy`, `sigma_xx`, `sigma_yy`, `sigma_xy` or `von_mises`.
    pub quantity: Option<String>,
}

/// `[estimate]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimateSpec {
    /// `higher-degree` (default) or `none`.
    pub method: Option<String>,
    /// Estimated relative e_inf above which the run is warned (default 1e-2).
    pub threshold: Option<f64>,
}

/// Exactly `N` numbers: a longer or shorter array is an error (serde's fixed arrays
/// would drop the extra elements of a TOML array silently).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Numbers<const N: usize>(pub [f64; N]);

impl<'de, const N: usize> Deserialize<'de> for Numbers<N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Vec::<f64>::deserialize(d)?;
        let n = v.len();
        let expected = format!("exactly {N} numbers");
        v.try_into().map(Numbers).map_err(|_| D::Error::invalid_length(n, &expected.as_str()))
    }
}

/// A point `[x, y]`.
pub type PointSpec = Numbers<2>;

/// A number, or a formula in quotes (see `expression`).
#[derive(Debug, Deserialize, Clone, PartialEq)]
#[serde(untagged, expecting = "a number or a formula in quotes")]
pub enum NumberOrFormula {
    /// A number.
    Number(f64),
    /// A formula.
    Formula(String),
}

/// An affine field `c0 + cx x + cy y` per component.
#[derive(Debug, Deserialize, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct AffineSpec {
    /// Coefficients `[c0, cx, cy]` of the x component.
    pub x: Numbers<3>,
    /// Coefficients `[c0, cx, cy]` of the y component.
    pub y: Numbers<3>,
}

/// An initial field: affine coefficients, or a vector of numbers or formulas.
#[derive(Debug, Deserialize, Clone)]
#[serde(untagged, expecting = "a vector [x, y] of numbers or formulas, or a table { x = [c0, cx, cy], y = [c0, cx, cy] }")]
pub enum InitialSpec {
    /// `{ x = [c0, cx, cy], y = [c0, cx, cy] }`.
    Affine(AffineSpec),
    /// `[ux, uy]`, numbers or formulas in x, y.
    Vector(Vec<NumberOrFormula>),
}

/// `[dynamics]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicsSpec {
    /// Mass density (kg/m^3).
    pub density: Option<f64>,
    /// Final time (s).
    pub end_time: Option<f64>,
    /// `emu`, `verlet` or `rk4`.
    pub integrator: Option<String>,
    /// Fixed time step (s); default a fraction of the stable step.
    pub time_step: Option<f64>,
    /// Fraction of the stable step used when `time_step` is not given.
    pub safety: Option<f64>,
    /// Initial displacement, default zero.
    pub initial_displacement: Option<InitialSpec>,
    /// Initial velocity, default zero.
    pub initial_velocity: Option<InitialSpec>,
    /// N: the .pvd series holds N + 1 states, t = 0 to the end (default 10; 0: the final state only).
    pub snapshots: Option<usize>,
    /// Write a snapshot every k steps instead (exclusive with `snapshots`).
    pub snapshot_every: Option<usize>,
}

/// `[peridynamics]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeridynamicsSpec {
    /// Horizon delta (m).
    pub horizon: Option<f64>,
    /// Ratio delta / h (default 3).
    pub m: Option<f64>,
    /// `plain` or `regularised`.
    pub kernel: Option<String>,
    /// Exponent of the regularised kernel (default -3).
    pub alpha: Option<f64>,
    /// Quadrature rule name.
    pub quadrature: Option<String>,
    /// `none` or `volume`.
    pub correction: Option<String>,
    /// Linear solver of the peridynamic system (default BiCGSTAB + ILU(0)).
    pub solver: Option<SolverSpec>,
    /// Bond force: `linear` (default) or `bond-stretch` (nonlinear).
    pub force: Option<String>,
    /// `auto` (default), `bond-based` or `lps` (the linear peridynamic solid).
    pub solid: Option<String>,
    /// `fictitious` (static default) or `surface` (dynamic default).
    pub boundary: Option<String>,
    /// `[peridynamics.fracture]`: bonds that break, pre-cracks.
    pub fracture: Option<FractureSpec>,
    /// A perturbed lattice: offsets of up to `perturbation h / 2` (0 to 1).
    pub perturbation: Option<f64>,
    /// `lattice` (default) or `delaunay`.
    pub points: Option<String>,
    /// Cut-cell weights on the lattice (default false).
    pub cut_cells: Option<bool>,
}

/// `[peridynamics.fracture]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FractureSpec {
    /// The critical stretch `s0`.
    pub critical_stretch: Option<f64>,
    /// The energy release rate `G0` (J/m^2), from which `s0` follows.
    pub energy_release_rate: Option<f64>,
    /// Pre-cracks `[x0, y0, x1, y1]`.
    pub cracks: Option<Vec<[f64; 4]>>,
}

/// `[domain]`: a list of regions combined left to right.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DomainSpec {
    /// `[[domain.region]]` entries.
    pub region: Vec<RegionSpec>,
}

/// `[[domain.region]]`: one primitive and how it combines with the regions before it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionSpec {
    /// `rectangle`, `disc` or `polygon`.
    pub shape: String,
    /// `union` (default), `subtract` or `intersect`.
    pub op: Option<String>,
    /// Rectangle corner with the smallest coordinates.
    pub min: Option<PointSpec>,
    /// Rectangle corner with the largest coordinates.
    pub max: Option<PointSpec>,
    /// Disc centre.
    pub center: Option<PointSpec>,
    /// Disc radius.
    pub radius: Option<f64>,
    /// Polygon vertices (either orientation).
    pub vertices: Option<Vec<PointSpec>>,
    /// Boundary part name of a disc.
    pub name: Option<String>,
    /// Part names of a rectangle's edges (keys `bottom`, `right`, `top`, `left`) ...
    pub names: Option<RectangleNames>,
    /// ... or of a polygon's edges (edge k runs from vertex k to vertex k+1).
    pub edge_names: Option<Vec<String>>,
}

/// Renamed rectangle edges.
#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct RectangleNames {
    /// Edge `y = min.y`.
    pub bottom: Option<String>,
    /// Edge `x = max.x`.
    pub right: Option<String>,
    /// Edge `y = max.y`.
    pub top: Option<String>,
    /// Edge `x = min.x`.
    pub left: Option<String>,
}

/// `[nodes]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodesSpec {
    /// Target spacing (m).
    pub spacing: Option<f64>,
    /// Approximate node count (alternative to `spacing`).
    pub count: Option<usize>,
    /// `grid` or `scattered`.
    pub fill: Option<String>,
    /// Random seed.
    pub seed: Option<u64>,
    /// Relaxation sweeps.
    pub relax: Option<usize>,
    /// Graded spacing towards boundary parts or points.
    pub refine: Option<RefineSpec>,
}

/// `[nodes.refine]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RefineSpec {
    /// Spacing at the targets (m).
    pub spacing: Option<f64>,
    /// Spacing gained per unit of distance from the targets.
    pub growth: Option<f64>,
    /// Boundary parts to refine towards.
    pub near: Option<Vec<String>>,
    /// Points to refine towards.
    pub points: Option<Vec<PointSpec>>,
}

/// `[approximation]`.
#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct ApproximationSpec {
    /// `monomials`, `tensor`, `phs`, `gaussian`, `mq`, `imq`.
    pub basis: Option<String>,
    /// Polynomial degree (of the least-squares basis, or of the RBF-FD augmentation).
    pub degree: Option<u32>,
    /// PHS exponent: `phi(r) = r^exponent`.
    pub exponent: Option<u32>,
    /// RBF shape parameter in units of the local spacing.
    pub shape: Option<f64>,
    /// `gaussian` or `none`.
    pub weight: Option<String>,
    /// Gaussian weight width in units of the local spacing.
    pub sigma: Option<f64>,
    /// Support size n.
    pub support: Option<usize>,
    /// Ghost nodes outside traction boundaries.
    pub ghost_nodes: Option<bool>,
    /// `auto`, `displacement` or `displacement-pressure`.
    pub formulation: Option<String>,
    /// `tau` of the displacement-pressure form's continuity stabilisation.
    pub pressure_stabilisation: Option<f64>,
}

/// `[material]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Young's modulus (Pa).
    #[serde(rename = "E")]
    pub young: Option<f64>,
    /// Poisson's ratio.
    pub nu: Option<f64>,
    /// First Lame parameter of the 3D solid (Pa).
    pub lambda: Option<f64>,
    /// Shear modulus (Pa).
    pub mu: Option<f64>,
    /// `stress` or `strain`.
    pub plane: String,
}

/// A 2-vector (numbers or formulas) or the word `"exact"`.
#[derive(Debug, Deserialize, Clone)]
#[serde(untagged, expecting = "a vector [x, y] of numbers or formulas in quotes, or the word \"exact\"")]
pub enum VectorOrExact {
    /// Components (the length is checked in `validate`).
    Vector(Vec<NumberOrFormula>),
    /// A word (only `exact` is valid).
    Word(String),
}

/// `[[boundary]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    /// Boundary part name.
    pub part: String,
    /// `displacement`, `traction` or `mixed`.
    pub kind: String,
    /// For `mixed`: condition on the x component (`displacement` or `traction`).
    pub x: Option<String>,
    /// For `mixed`: condition on the y component.
    pub y: Option<String>,
    /// Value (m or Pa; numbers or formulas in x, y) or `"exact"`; default `[0, 0]`.
    pub value: Option<VectorOrExact>,
}

/// `[solver]`.
#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// `lu` or `bicgstab`.
    pub kind: Option<String>,
    /// `ilu0`, `ilut` or `jacobi`.
    pub preconditioner: Option<String>,
    /// ILUT drop tolerance.
    pub drop: Option<f64>,
    /// ILUT fill per row.
    pub fill: Option<usize>,
    /// Relative residual tolerance.
    pub tolerance: Option<f64>,
    /// Iteration limit.
    pub max_iterations: Option<usize>,
    /// GMRES restart length.
    pub restart: Option<usize>,
    /// Row equilibration.
    pub equilibrate: Option<bool>,
    /// The operator the multigrid is built on: `auto`, `system`, `low-order`.
    pub multigrid: Option<String>,
}

/// `[output]`.
#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Fields: `displacement`, `strain`, `stress`, `von_mises`, `error`.
    pub fields: Option<Vec<String>>,
}

/// `[exact]`: the solution's name and its parameters (which parameters a solution
/// takes is checked in `validate`, against the solution's own list).
#[derive(Debug, Deserialize)]
pub struct ExactSpec {
    /// Solution name (`cantilever`, `kirsch`, ...).
    pub kind: String,
    /// Every other key: the solution's parameters.
    #[serde(flatten)]
    pub parameters: std::collections::BTreeMap<String, toml::Value>,
}
