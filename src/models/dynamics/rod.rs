//! The seed's closed-form rod (seed 000, example 4.1.6 and sec. 4.2): `Omega = (0, 1)`,
//! every point interacting with every other through the linearised bond-stretch force
//! `f = c / |x' - x| (u(x') - u(x))`,
//!
//! ```text
//! rho u_tt = int_0^1 c / |x' - x| (u(x') - u(x)) dx',   u(x, 0) = 0,   u_t(x, 0) = 10 (0.5 - x),
//! u(x, t) = 10 (0.5 - x) sin(omega t) / omega,   omega = sqrt(2 c / rho).
//! ```
//!
//! With `N` midpoint nodes `x_i = (i + 1/2)/N` of weight `1/N` the discrete force of the
//! linear field is exact (`sum_j sign(x_j - x_i) / N = (N - 1 - 2 i)/N`), so every error
//! is the time integrator's. Energies (definition 4.1.5): `E_kin = int rho v^2 / 2`,
//! `E_el = 1/2 int int c (u(x') - u(x))^2 / (2 |x' - x|)`; `E_kin(0) = 25 rho / 6`
//! (the midpoint sum gives `25 rho / 6 (1 - 1/N^2)`).

use super::SecondOrderSystem;
use rayon::prelude::*;

/// The discretised rod.
#[derive(Debug, Clone, Copy)]
pub struct Rod {
    /// Number of nodes.
    pub nodes: usize,
    /// Bond constant `c_{1,delta}`.
    pub c: f64,
    /// Density.
    pub rho: f64,
}

impl Rod {
    /// Node position `x_i`.
    pub fn x(&self, i: usize) -> f64 {
        (i as f64 + 0.5) / self.nodes as f64
    }

    /// `omega = sqrt(2 c / rho)`.
    pub fn omega(&self) -> f64 {
        (2.0 * self.c / self.rho).sqrt()
    }

    /// Exact `(u, v, a)` at node `i` and time `t`.
    pub fn exact(&self, i: usize, t: f64) -> (f64, f64, f64) {
        let (w, s) = (self.omega(), 10.0 * (0.5 - self.x(i)));
        (s * (w * t).sin() / w, s * (w * t).cos(), -s * w * (w * t).sin())
    }

    /// Initial velocity `10 (0.5 - x_i)`.
    pub fn initial_velocity(&self) -> Vec<f64> {
        (0..self.nodes).map(|i| 10.0 * (0.5 - self.x(i))).collect()
    }

    /// `(E_kin, E_el)` of the discrete state.
    pub fn energies(&self, u: &[f64], v: &[f64]) -> (f64, f64) {
        let w = 1.0 / self.nodes as f64;
        let kinetic = v.iter().map(|v| 0.5 * self.rho * v * v * w).sum();
        let elastic = (0..self.nodes)
            .into_par_iter()
            .map(|i| {
                let own: f64 = (0..self.nodes)
                    .filter(|&j| j != i)
                    .map(|j| 0.5 * self.c * (u[j] - u[i]).powi(2) / (self.x(j) - self.x(i)).abs() * w)
                    .sum();
                0.5 * own * w
            })
            .sum();
        (kinetic, elastic)
    }
}

impl SecondOrderSystem for Rod {
    fn len(&self) -> usize {
        self.nodes
    }

    fn acceleration(&self, _t: f64, u: &[f64], a: &mut [f64]) {
        let w = 1.0 / self.nodes as f64;
        a.par_iter_mut().enumerate().for_each(|(i, a)| {
            *a = (0..self.nodes).filter(|&j| j != i).map(|j| self.c / (self.x(j) - self.x(i)).abs() * (u[j] - u[i]) * w).sum::<f64>()
                / self.rho;
        });
    }
}
