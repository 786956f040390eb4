//! Linear elasticity, independent of any discretisation: material and planar model,
//! boundary conditions of the boundary parts, the layout of the unknowns, and
//! strain, stress and von Mises stress from a displacement gradient.

pub mod conditions;
pub mod dofs;
pub mod material;
pub mod stress;
