//! The bond laws of explicit peridynamics (module docs of [`super::dynamics`]): each
//! bond's force, its flag at the critical stretch and its micropotential, as the force
//! loop's laws ([`super::block::BondLaw`]) and one bond at a time (breaking, energies).
//!
//! ```text
//! linear:        f_ij = c_ij (xi . eta) xi,                       w = c (xi . eta)^2 / 2
//! bond-stretch:  f_ij = c_ij |xi|^3 s (xi + eta) / |xi + eta|,    w = c |xi|^4 s^2 / 2
//! ```

/// The linear law of the force loop ([`super::block::BondLaw`]): `g = V_i c (xi . eta) xi`
/// (module docs); flagged where live (`c != 0`) and at `s0` (`xi . eta >= s0 |xi|^2`)
/// when `FLAG`; the energy `V_i c (xi . eta)^2 / 2` when `ENERGY`, else 0.
#[inline(always)]
pub(super) fn linear_law<const FLAG: bool, const ENERGY: bool>(
    s0: f64,
) -> impl Fn(f64, [f64; 2], [f64; 2], f64) -> ([f64; 2], bool, f64) + Sync {
    move |c, xi, eta, vi| {
        let p = xi[0] * eta[0] + xi[1] * eta[1];
        if FLAG {
            let cp = c * p;
            let e = if ENERGY { 0.5 * vi * cp * p } else { 0.0 };
            // Live and at s0 (a broken bond, c = 0, stays stretched: not flagged).
            ([vi * cp * xi[0], vi * cp * xi[1]], (cp != 0.0) & (p >= s0 * (xi[0] * xi[0] + xi[1] * xi[1])), e)
        } else {
            let vcp = vi * c * p;
            let e = if ENERGY { 0.5 * vcp * p } else { 0.0 };
            ([vcp * xi[0], vcp * xi[1]], false, e)
        }
    }
}

/// The bond-stretch law of the force loop: `V_i` times [`bond_stretch_force`], flagged at
/// `s0` (infinite: never), with its energy `V_i w` when `ENERGY`, else 0.
#[inline(always)]
pub(super) fn bond_stretch_law<const ENERGY: bool>(s0: f64) -> impl Fn(f64, [f64; 2], [f64; 2], f64) -> ([f64; 2], bool, f64) + Sync {
    move |c, xi, eta, vi| {
        let (g, at, w) = bond_stretch_force(c, xi, eta, s0);
        ([vi * g[0], vi * g[1]], at, if ENERGY { vi * w } else { 0.0 })
    }
}

/// The bond-stretch force `c |xi|^3 s (xi + eta) / |xi + eta|` (module docs), whether
/// the bond is live and at `s0` or beyond (`|xi + eta| - |xi| >= s0 |xi|`), and its
/// micropotential `c |xi|^4 s^2 / 2 = c |xi|^2 (|xi + eta| - |xi|)^2 / 2`.
#[inline(always)]
pub(super) fn bond_stretch_force(c: f64, xi: [f64; 2], eta: [f64; 2], s0: f64) -> ([f64; 2], bool, f64) {
    let r2 = xi[0] * xi[0] + xi[1] * xi[1];
    let r = r2.sqrt();
    let y = [xi[0] + eta[0], xi[1] + eta[1]];
    let ry = (y[0] * y[0] + y[1] * y[1]).sqrt();
    // c |xi|^3 s / |xi + eta|, s = (|xi + eta| - |xi|) / |xi|.
    let k = c * r2 * (ry - r) / ry;
    ([k * y[0], k * y[1]], (c != 0.0) & (ry - r >= s0 * r), 0.5 * c * r2 * (ry - r) * (ry - r))
}

/// The linear law's micropotential `c (xi . eta)^2 / 2` (module docs) and the linearised
/// stretch `xi . eta / |xi|^2`.
#[inline(always)]
pub(super) fn linear_energy(c: f64, xi: [f64; 2], eta: [f64; 2]) -> (f64, f64) {
    let p = xi[0] * eta[0] + xi[1] * eta[1];
    (0.5 * c * p * p, p / (xi[0] * xi[0] + xi[1] * xi[1]))
}

/// The bond-stretch micropotential `c |xi|^4 s^2 / 2` (module docs) and the stretch `s`.
#[inline(always)]
pub(super) fn bond_stretch_energy(c: f64, xi: [f64; 2], eta: [f64; 2]) -> (f64, f64) {
    let r = (xi[0] * xi[0] + xi[1] * xi[1]).sqrt();
    let s = (((xi[0] + eta[0]).powi(2) + (xi[1] + eta[1]).powi(2)).sqrt() - r) / r;
    (0.5 * c * r.powi(4) * s * s, s)
}
