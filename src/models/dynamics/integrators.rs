//! One step of each explicit scheme for `u_tt = a(t, u)`:
//!
//! ```text
//! EMU (seed 000, alg. 4.3.1):  v += dt a(u);  u += dt v                    (a from the step start)
//! Stormer-Verlet:              u += dt v + dt^2/2 a;  a' = a(u);  v += dt (a + a')/2
//! RK4:                         classical Runge-Kutta on y = (u, v), y' = (v, a(u))
//! ```
//!
//! Observed orders on the seed's closed-form rod (table 4.3.1) for `(u, v, a)`:
//! EMU (2, 1, 1), Verlet (2, 2, 2), RK4 (4, 4, 4); reproduced in `tests/dynamics.rs`.
//!
//! Stability of the central-difference family (EMU and Verlet) needs
//! `dt <= 2 / omega_max`; classical RK4 is stable on the imaginary axis up to
//! `2 sqrt(2) / omega_max`. [`Integrator::stability_factor`] returns the ratio to the
//! central-difference limit.

use super::{SecondOrderSystem, State};
use crate::scene::choice::choice;
use rayon::prelude::*;

choice! {
    /// An explicit time integrator.
    pub enum Integrator("dynamics.integrator", default Some(Integrator::Verlet), serde "lowercase") {
        /// Velocity by forward, displacement by backward differences (symplectic Euler).
        Emu = "emu" => "v += dt a(u), then u += dt v (seed 000, alg. 4.3.1); orders 2, 1, 1 in u, v, a",
        /// Stormer-Verlet (velocity form).
        Verlet = "verlet" => "Stormer-Verlet (velocity form); second order, bounded energy error",
        /// Classical fourth-order Runge-Kutta.
        Rk4 = "rk4" => "classical fourth-order Runge-Kutta; stable to sqrt(2) times the central-difference step",
    }
}

impl Integrator {
    /// Global order of accuracy in `dt` (of the displacement over a fixed time).
    pub fn order(self) -> u32 {
        match self {
            Integrator::Emu => 1,
            Integrator::Verlet => 2,
            Integrator::Rk4 => 4,
        }
    }

    /// Largest stable `dt` relative to the central-difference limit `2 / omega_max`.
    pub fn stability_factor(self) -> f64 {
        match self {
            Integrator::Emu | Integrator::Verlet => 1.0,
            Integrator::Rk4 => 2f64.sqrt(),
        }
    }

    /// Relative error per radian of an oscillation `u'' = -omega^2 u` integrated at
    /// `h = omega dt`, to leading order: Verlet's numerical frequency satisfies
    /// `sin(omega_h dt / 2) = h / 2`, a phase error `h^2 / 24`; RK4 misses the `h^5 / 120`
    /// term of `exp(i h)` per step, `h^4 / 120` per radian; `emu` (symplectic Euler)
    /// has Verlet's frequency but a velocity half a step off, a first-order `h / 2`.
    pub fn error_per_radian(self, h: f64) -> f64 {
        match self {
            Integrator::Emu => h / 2.0,
            Integrator::Verlet => h * h / 24.0,
            Integrator::Rk4 => h.powi(4) / 120.0,
        }
    }

    /// The largest `h = omega dt` whose [`Integrator::error_per_radian`] is `error`.
    pub fn step_for_error(self, error: f64) -> f64 {
        match self {
            Integrator::Emu => 2.0 * error,
            Integrator::Verlet => (24.0 * error).sqrt(),
            Integrator::Rk4 => (120.0 * error).powf(0.25),
        }
    }

    /// Force evaluations per step.
    pub fn evaluations(self) -> usize {
        match self {
            Integrator::Emu | Integrator::Verlet => 1,
            Integrator::Rk4 => 4,
        }
    }

    /// Advance `s` by `dt`.
    pub fn step(self, system: &dyn SecondOrderSystem, s: &mut State, dt: f64) {
        match self {
            Integrator::Emu => {
                // The acceleration at the start of the step, kept as the reported one.
                system.acceleration(s.t, &s.u, &mut s.a);
                axpy(&mut s.v, dt, &s.a);
                axpy(&mut s.u, dt, &s.v);
                s.t += dt;
            }
            Integrator::Verlet => {
                s.u.par_iter_mut().zip(&s.v).zip(&s.a).for_each(|((u, v), a)| *u += dt * v + 0.5 * dt * dt * a);
                s.t += dt;
                let mut next = vec![0.0; s.a.len()];
                system.acceleration(s.t, &s.u, &mut next);
                s.v.par_iter_mut().zip(&s.a).zip(&next).for_each(|((v, a0), a1)| *v += 0.5 * dt * (a0 + a1));
                s.a = next;
            }
            Integrator::Rk4 => {
                let n = s.u.len();
                let (t, u0, v0) = (s.t, &s.u, &s.v);
                let k1u = v0.clone();
                let k1v = s.a.clone();
                let stage = |c: f64, ku: &[f64], kv: &[f64]| -> (Vec<f64>, Vec<f64>) {
                    let u: Vec<f64> = (0..n).into_par_iter().map(|i| u0[i] + c * dt * ku[i]).collect();
                    let v: Vec<f64> = (0..n).into_par_iter().map(|i| v0[i] + c * dt * kv[i]).collect();
                    (u, v)
                };
                let accel = |time: f64, u: &[f64]| {
                    let mut a = vec![0.0; n];
                    system.acceleration(time, u, &mut a);
                    a
                };
                let (u2, k2u) = stage(0.5, &k1u, &k1v);
                let k2v = accel(t + 0.5 * dt, &u2);
                let (u3, k3u) = stage(0.5, &k2u, &k2v);
                let k3v = accel(t + 0.5 * dt, &u3);
                let (u4, k4u) = stage(1.0, &k3u, &k3v);
                let k4v = accel(t + dt, &u4);
                let combine = |y: &mut [f64], k1: &[f64], k2: &[f64], k3: &[f64], k4: &[f64]| {
                    y.par_iter_mut().enumerate().for_each(|(i, y)| *y += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
                };
                combine(&mut s.u, &k1u, &k2u, &k3u, &k4u);
                combine(&mut s.v, &k1v, &k2v, &k3v, &k4v);
                s.t += dt;
                system.acceleration(s.t, &s.u, &mut s.a);
            }
        }
    }
}

fn axpy(y: &mut [f64], alpha: f64, x: &[f64]) {
    y.par_iter_mut().zip(x).for_each(|(y, x)| *y += alpha * x);
}
