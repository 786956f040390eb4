//! Linear elasticity on the node set: material, unknown layout, boundary equations,
//! equation rows, and stresses.

pub mod conditions;
pub mod dofs;
pub mod material;
pub mod rows;
pub mod stress;
