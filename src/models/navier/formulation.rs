//! Which unknowns the Navier model solves for.
//!
//! * **Displacement** (`u, v` per node): `(lambda + mu) grad div u + mu lap u + f = 0`.
//!   As `nu -> 1/2` in plane strain, `lambda / mu -> inf`: the stress `lambda div u`
//!   multiplies a small, inaccurate divergence and the errors grow like `lambda / mu`
//!   (docs/methods/incompressible.md).
//! * **Displacement-pressure** (`u, v, p` per node) with `p = -lambda div u`:
//!
//!   ```text
//!   mu lap u + mu grad div u - grad p + f = 0      (momentum, where Navier rows are)
//!   a mu div u + b p = 0                            (continuity, every node)
//!   d/dn (a mu div u + b p) = 0                      (in the ghost's row, nodes with a ghost)
//!   sigma = -p I + mu (grad u + grad u^T)           (tractions and stress)
//!   ```
//!
//!   with `a = lambda / (lambda + mu)`, `b = mu / (lambda + mu)`
//!   ([`Material::pressure_weights`]), finite up to and including `nu = 1/2`, where
//!   the continuity row is `div u = 0`. The pressure lives on the same nodes as the
//!   displacement (equal order); the continuity rows at boundary nodes close it
//!   without a pressure boundary condition. A ghost's third unknown takes the normal
//!   derivative of the continuity equation at its boundary node: the continuity
//!   equation written at the ghost itself (an extrapolating stencil) gave larger
//!   errors at `nu = 1/2` (docs/methods/incompressible.md).
//!
//! **Pressure stabilisation.** Equal-order collocation has no inf-sup guarantee: at
//! `nu = 1/2` the pressure near the Lame ring's bore oscillated and the stress error
//! grew (docs/methods/incompressible.md). The
//! continuity row of every node with second-derivative shapes (interior nodes and
//! nodes with a ghost) gets a consistent pressure-Laplacian term, the strong-form
//! analogue of pressure-stabilised Petrov-Galerkin:
//!
//!   ```text
//!   a div u + b p / mu - tau h^2 ((a + 2b) lap p - a div f) / mu = 0
//!   ```
//!
//! `h` the node's local spacing, `tau` = `approximation.pressure_stabilisation`
//! ([`PRESSURE_STABILISATION`]). The divergence of the momentum equation with
//! `div u = -(b / a) p / mu` gives `(a + 2b) lap p = a div f` for the exact solution
//! of a homogeneous solid, so the term vanishes on it and the order is kept; `div f`
//! is taken with the node's gradient shapes over the body force at its support (zero
//! for a constant body force). It damps the pressure's oscillating modes, which the
//! continuity rows alone do not see.

use crate::scene::choice::choice;
use crate::physics::elasticity::dofs::Unknowns;
use crate::physics::elasticity::material::{Material, PlaneModel};

choice! {
    /// The unknowns of the Navier model (module docs).
    pub enum Formulation("approximation.formulation", default Some(Formulation::Auto), serde "kebab-case") {
        Auto = "auto" => "displacement-pressure in plane strain from nu = 0.45 on (static runs), displacement otherwise",
        Displacement = "displacement" => "u, v per node: the Navier equation; errors grow like lambda / mu as nu -> 0.5",
        DisplacementPressure = "displacement-pressure" => "u, v, p per node with p = -lambda div u; valid up to nu = 0.5 (static plane strain)",
    }
}

/// Poisson's ratio from which `auto` takes the displacement-pressure form in plane
/// strain (docs/methods/incompressible.md: where the two forms' errors cross).
pub const AUTO_FROM_POISSON: f64 = 0.45;

/// Default `tau` of the continuity rows' pressure stabilisation (module docs), in
/// squared local spacings: it brings the near-incompressible Lame ring to the errors of
/// nu = 0.3 and converges cleanly over five levels on Lame and manufactured_traction
/// (docs/notebook/round2-pressure-stabilisation.md, "Choice of tau").
pub const PRESSURE_STABILISATION: f64 = 0.1;

/// Largest `tau` accepted: the measured range. Above it the pressure Laplacian drowns
/// the continuity equation, `div u` is barely enforced and the errors grow (warned by
/// the estimate; docs/methods/incompressible.md).
pub const MAX_PRESSURE_STABILISATION: f64 = 1.0;

impl Formulation {
    /// The unknowns this choice solves for with `material` (`auto` resolved).
    pub fn unknowns(self, material: &Material) -> Unknowns {
        match self {
            Formulation::Displacement => Unknowns::Displacement,
            Formulation::DisplacementPressure => Unknowns::DisplacementPressure,
            Formulation::Auto => {
                if material.plane == PlaneModel::Strain && material.elastic.poisson >= AUTO_FROM_POISSON {
                    Unknowns::DisplacementPressure
                } else {
                    Unknowns::Displacement
                }
            }
        }
    }
}
