//! The two models of the solid and how a run is made with them: explicit time
//! integration shared by both ([`dynamics`]), the local Navier model by meshless
//! collocation ([`navier`]), linear peridynamics ([`peridynamics`]), the memory a run
//! will need ([`resources`]), and the one dispatch static/dynamic x Navier/peridynamics
//! ([`dispatch`]).

pub mod dispatch;
pub mod dynamics;
pub mod navier;
pub mod peridynamics;
pub mod resources;
