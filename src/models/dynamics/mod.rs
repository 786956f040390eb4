//! Explicit time integration of `rho u_tt = F(u) + b` (seed 000, sec. 4.3) for any
//! semi-discrete system: the peridynamic force, the condensed MLSM operator, or a
//! one-dimensional model problem.
//!
//! A [`SecondOrderSystem`] gives the acceleration `a(t, u) = (F(u) + b(t)) / rho` of a
//! flat vector of unknowns; [`Integrator`] advances a [`State`] `(t, u, v, a)` by one
//! step. `a` holds the acceleration of the last force evaluation of the scheme (for
//! EMU the one at the start of the step, which is why its order in `a` is 1, as in the
//! seed's table 4.3.1).

pub mod driver;
pub mod history;
pub mod integrators;
pub mod params;
pub mod rod;

pub use driver::INTEGRATE;
pub use integrators::Integrator;
pub use params::DynamicsParams;

/// A semi-discrete second-order system `u_tt = a(t, u)`.
pub trait SecondOrderSystem: Sync {
    /// Number of scalar unknowns.
    fn len(&self) -> usize;
    /// True for a system without unknowns.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Write `a(t, u)` into `a`.
    fn acceleration(&self, t: f64, u: &[f64], a: &mut [f64]);
    /// Why the step from `t0` to `t1` became non-finite, when the system knows (a load
    /// formula that is not finite at some time in the step); `None`: the integration
    /// itself diverged.
    fn explain(&self, _t0: f64, _t1: f64) -> Option<crate::stages::RunError> {
        None
    }
    /// Bring the system up to date with the state a step reached (bonds that break,
    /// `super::super::peridynamics::fracture`), re-evaluating `state.a` if that changed
    /// the forces; called after every step. Returns whether it changed them (the energy
    /// history then records the step). Nothing by default.
    fn settle(&self, _state: &mut State) -> bool {
        false
    }
    /// Whether the energies of a state cost no pass over the operator, because the
    /// evaluation that ended the step kept them (the energy history then has a row at
    /// every step, [`driver::energy_every`]). No by default.
    fn energies_from_evaluation(&self) -> bool {
        false
    }
}

/// Time, displacement, velocity and the last acceleration.
#[derive(Debug, Clone, PartialEq)]
pub struct State {
    /// Time.
    pub t: f64,
    /// Displacements.
    pub u: Vec<f64>,
    /// Velocities.
    pub v: Vec<f64>,
    /// Acceleration of the last force evaluation.
    pub a: Vec<f64>,
}

impl State {
    /// The state at `t0` with displacement `u` and velocity `v`; `a = a(t0, u)`.
    pub fn new(system: &dyn SecondOrderSystem, t0: f64, u: Vec<f64>, v: Vec<f64>) -> State {
        let mut a = vec![0.0; u.len()];
        system.acceleration(t0, &u, &mut a);
        State { t: t0, u, v, a }
    }
}
