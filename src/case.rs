//! The physical problem of a scene, independent of any discretisation: the solid,
//! its material, body force and boundary conditions, the closed-form solution it is
//! checked against, the time settings, and the fields the user asked for. Both
//! models read a [`Case`]; each adds its own discretisation parameters
//! (`navier::NavierParams`, `peridynamics::PdParams`).

use crate::choice::choice;
use crate::domain::Domain;
use crate::dynamics::DynamicsParams;
use crate::elasticity::conditions::{BoundaryCondition, Value};
use crate::elasticity::material::Material;
use crate::exact::{ExactSolution, NamedSolution};
use serde::Serialize;

/// Output fields a run writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct Outputs {
    /// Displacement vector.
    pub displacement: bool,
    /// Strain components.
    pub strain: bool,
    /// Stress components.
    pub stress: bool,
    /// Von Mises stress.
    pub von_mises: bool,
    /// Error fields and norms against the exact solution.
    pub error: bool,
}

choice! {
    /// A field of `output.fields`.
    pub enum OutputField("output.fields[k]", default None, note "displacement, stress, von_mises, and error when the scene has [exact]") {
        /// Displacement (always written).
        Displacement = "displacement" => "the displacement vector (always written)",
        /// Strain components.
        Strain = "strain" => "eps_xx, eps_yy, eps_xy",
        /// Stress components.
        Stress = "stress" => "sigma_xx, sigma_yy, sigma_xy (and sigma_zz in plane strain)",
        /// Von Mises stress.
        VonMises = "von_mises" => "von Mises stress",
        /// Errors against the exact solution.
        Error = "error" => "exact displacement and the error fields and norms (needs [exact])",
    }
}

impl Outputs {
    /// Request `field`.
    pub fn request(&mut self, field: OutputField) {
        let slot = match field {
            OutputField::Displacement => &mut self.displacement,
            OutputField::Strain => &mut self.strain,
            OutputField::Stress => &mut self.stress,
            OutputField::VonMises => &mut self.von_mises,
            OutputField::Error => &mut self.error,
        };
        *slot = true;
    }

    /// Whether post-processing needs the displacement gradient.
    pub fn needs_gradient(&self) -> bool {
        self.strain || self.stress || self.von_mises || self.error
    }
}

/// The solid, its loads and what to report (see the module docs).
#[derive(Debug, Clone)]
pub struct Case {
    /// The solid.
    pub domain: Domain,
    /// Material.
    pub material: Material,
    /// Body force.
    pub body_force: Value,
    /// Condition of each boundary part, indexed like `domain.parts`.
    pub conditions: Vec<BoundaryCondition>,
    /// Closed-form solution, if any.
    pub exact: Option<NamedSolution>,
    /// Requested fields.
    pub outputs: Outputs,
    /// Time-dependent run settings, when the scene has a `[dynamics]` table.
    pub dynamics: Option<DynamicsParams>,
}

impl Case {
    /// The exact solution the scene names, if any (its parameters were validated).
    pub fn exact_solution(&self) -> Option<Box<dyn ExactSolution>> {
        self.exact.as_ref().map(|e| e.build(self.material).expect("validated exact solution parameters"))
    }
}
