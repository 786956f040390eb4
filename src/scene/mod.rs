//! The scene file a user writes, from text to a validated run: the option names of
//! every choice ([`choice`]), the formulas a scene may hold ([`expression`]), and the
//! TOML scene -> [`problem::Problem`] (parsing, presets, validation, [`problem`]).

pub mod choice;
pub mod expression;
pub mod problem;
