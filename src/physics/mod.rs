//! The solid and what is known about it, independent of any discretisation: material,
//! boundary conditions, the unknown layout and stress ([`elasticity`]), closed-form
//! and manufactured solutions ([`exact`]), and a scene's physical problem ([`case`]).

pub mod case;
pub mod elasticity;
pub mod exact;
