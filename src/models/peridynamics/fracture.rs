//! Brittle fracture in bond-based peridynamics: pre-cracks and bonds that break for
//! good (seed 000, ch. 4: "a bond breaks for good once its stretch s >= s0").
//!
//! A bond's stretch is `s = (|xi + eta| - |xi|) / |xi|` under the bond-stretch law and its
//! linearisation `s = xi . eta / |xi|^2` under the linear law. After every time step the
//! bonds whose stretch at the new state is at least `s0` break, both directions at once
//! (their forces vanish from then on, and their energy is counted as released); the
//! acceleration is evaluated again when any broke. Each force evaluation records the
//! bonds at `s0` or beyond, so the check after the step reads only those bonds of the
//! last evaluation (Verlet and RK4 end the step with the evaluation at the new
//! state; `emu` evaluates at the start of the step, so its bonds break one step later).
//!
//! Critical stretch from the energy release rate `G0`: the energy of the bonds that
//! cross a unit length of a straight crack, each holding `w = lambda(r) r^4 s0^2 / 2`
//! (Silling and Askari 2005; Ha and Bobaru 2010 in 2D), is
//!
//! ```text
//! G0 = 2 int_0^delta int_z^delta int_0^acos(z/r) w(r) r dtheta dr dz = s0^2 int_0^delta lambda(r) r^6 dr,
//! ```
//!
//! so `s0 = sqrt(G0 / int_0^delta lambda(r) r^6 dr)`: for the plain kernel
//! (`lambda = c / r^3`) `s0 = sqrt(4 G0 / (c delta^4))`, Ha and Bobaru's
//! `sqrt(4 pi G0 / (9 E delta))` in plane stress and `sqrt(5 pi G0 / (12 E delta))` in
//! plane strain.
//!
//! A pre-crack is a segment no bond crosses: its bonds are broken from the start (static
//! runs: their coefficients are zero), as peer codes define pre-cracks.

use super::block::Flagged;
use super::family::Families;
use super::kernel::{radial_integral, Micromodulus};
use super::Kernel;
use crate::domain::{CsgOp, Domain, Point, Primitive};
use rayon::prelude::*;
use serde::Serialize;
use std::ops::Range;
use std::sync::{Mutex, RwLock, RwLockReadGuard};

/// The most pre-cracks a scene may give.
pub const MAX_CRACKS: usize = 8;

/// `[peridynamics.fracture]`: how bonds break and where the solid is cracked at the start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fracture {
    /// How the critical stretch is given; `None`: pre-cracks only, no bond breaks.
    pub breaking: Option<CriticalStretch>,
    /// Pre-cracks as segments `[x0, y0, x1, y1]`: the first `crack_count` entries.
    cracks: [[f64; 4]; MAX_CRACKS],
    crack_count: usize,
}

/// The critical stretch `s0`, given or from the energy release rate (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CriticalStretch {
    /// `s0` itself.
    Given(f64),
    /// `G0` in J/m^2 (N/m per unit thickness).
    EnergyReleaseRate(f64),
}

impl Serialize for Fracture {
    /// `{ breaking, cracks }`, the pre-cracks given and no more.
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut s = serializer.serialize_struct("Fracture", 2)?;
        s.serialize_field("breaking", &self.breaking)?;
        s.serialize_field("cracks", self.cracks())?;
        s.end()
    }
}

impl Fracture {
    /// Breaking as `breaking` says, with the pre-cracks `cracks` (at most [`MAX_CRACKS`]).
    pub fn new(breaking: Option<CriticalStretch>, cracks: &[[f64; 4]]) -> Option<Self> {
        if cracks.len() > MAX_CRACKS {
            return None;
        }
        let mut all = [[0.0; 4]; MAX_CRACKS];
        all[..cracks.len()].copy_from_slice(cracks);
        Some(Fracture { breaking, cracks: all, crack_count: cracks.len() })
    }

    /// The pre-cracks.
    pub fn cracks(&self) -> &[[f64; 4]] {
        &self.cracks[..self.crack_count]
    }

    /// What no bond of `domain` crosses from the start ([`Cuts`]).
    pub fn cuts<'a>(&'a self, domain: &'a Domain) -> Cuts<'a> {
        let notches =
            domain.regions.iter().skip(1).filter(|r| r.op == CsgOp::Subtract).map(|r| (&r.primitive, r.primitive.bounding_box())).collect();
        Cuts { cracks: self.cracks(), notches }
    }

    /// The critical stretch for `micromodulus` (module docs), when bonds break.
    pub fn critical_stretch(&self, micromodulus: &Micromodulus) -> Option<f64> {
        self.breaking.map(|b| match b {
            CriticalStretch::Given(s0) => s0,
            CriticalStretch::EnergyReleaseRate(g0) => (g0 / sixth_moment(micromodulus)).sqrt(),
        })
    }
}

/// `int_0^delta lambda(r) r^6 dr` of a calibrated kernel.
pub fn sixth_moment(m: &Micromodulus) -> f64 {
    match m.kernel {
        Kernel::Plain => m.constant * m.horizon.powi(4) / 4.0,
        Kernel::Regularised { alpha } => m.constant * m.horizon.powf(alpha + 7.0) * radial_integral(alpha + 1.0),
    }
}

/// What no bond crosses from the start: the pre-cracks and the regions cut out of the
/// solid (`op = "subtract"`: notches, slots, holes). A notch narrower than the horizon
/// would otherwise be bridged by the bonds across it (families are found by distance),
/// so in a scene with `[peridynamics.fracture]` a bond whose segment passes through
/// such a region is broken from the start, as one across a pre-crack.
pub struct Cuts<'a> {
    cracks: &'a [[f64; 4]],
    notches: Vec<(&'a Primitive, (Point, Point))>,
}

impl Cuts<'_> {
    /// Whether the bond from `a` to `b` crosses a pre-crack or passes through a region
    /// cut out of the solid.
    pub fn cut(&self, a: Point, b: Point) -> bool {
        self.cracks.iter().any(|c| segments_cross(a, b, [c[0], c[1]], [c[2], c[3]]))
            || self.notches.iter().any(|(p, (lo, hi))| {
                let apart = a[0].max(b[0]) < lo[0] || a[0].min(b[0]) > hi[0] || a[1].max(b[1]) < lo[1] || a[1].min(b[1]) > hi[1];
                !apart && passes_through(p, a, b)
            })
    }

    /// Zero the `coefficients` of the bonds of `families` (over the nodes at
    /// `positions`) that are cut; how many there were (both directions counted).
    pub fn break_precracked(&self, positions: &[Point], families: &Families, coefficients: &mut [f64]) -> usize {
        if self.cracks.is_empty() && self.notches.is_empty() {
            return 0;
        }
        let x = positions;
        let cut: Vec<usize> = (0..families.len())
            .into_par_iter()
            .flat_map_iter(|i| families.range(i).zip(families.of(i)).filter(move |(_, &j)| self.cut(x[i], x[j as usize])).map(|(b, _)| b))
            .collect();
        cut.iter().for_each(|&b| coefficients[b] = 0.0);
        cut.len()
    }
}

/// Whether the segment `a b` passes through the interior of `p`: a disc when the
/// segment comes nearer its centre than the radius; a rectangle or polygon when the
/// segment properly crosses one of its edges (both ends are material, so outside or on
/// its boundary).
fn passes_through(p: &Primitive, a: Point, b: Point) -> bool {
    let proper = |q0: Point, q1: Point| {
        let orient = |u: Point, v: Point, w: Point| (v[0] - u[0]) * (w[1] - u[1]) - (v[1] - u[1]) * (w[0] - u[0]);
        orient(q0, q1, a) * orient(q0, q1, b) < 0.0 && orient(a, b, q0) * orient(a, b, q1) < 0.0
    };
    let edges = |v: &[Point]| (0..v.len()).any(|k| proper(v[k], v[(k + 1) % v.len()]));
    match p {
        Primitive::Disc { center, radius } => {
            let ab = [b[0] - a[0], b[1] - a[1]];
            let t = (((center[0] - a[0]) * ab[0] + (center[1] - a[1]) * ab[1]) / (ab[0] * ab[0] + ab[1] * ab[1])).clamp(0.0, 1.0);
            let q = [a[0] + t * ab[0] - center[0], a[1] + t * ab[1] - center[1]];
            q[0].hypot(q[1]) < radius * (1.0 - 1e-12)
        }
        Primitive::Rectangle { min, max } => edges(&[*min, [max[0], min[1]], *max, [min[0], max[1]]]),
        Primitive::Polygon { vertices } => edges(vertices),
    }
}

/// Whether the segments `p0 p1` and `q0 q1` cross (share a point; a bond that ends
/// exactly on a crack crosses it).
fn segments_cross(p0: Point, p1: Point, q0: Point, q1: Point) -> bool {
    let orient = |a: Point, b: Point, c: Point| (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    let (d1, d2) = (orient(q0, q1, p0), orient(q0, q1, p1));
    let (d3, d4) = (orient(p0, p1, q0), orient(p0, p1, q1));
    let within =
        |a: Point, b: Point, c: Point| c[0] >= a[0].min(b[0]) && c[0] <= a[0].max(b[0]) && c[1] >= a[1].min(b[1]) && c[1] <= a[1].max(b[1]);
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        return true;
    }
    (d1 == 0.0 && within(q0, q1, p0))
        || (d2 == 0.0 && within(q0, q1, p1))
        || (d3 == 0.0 && within(p0, p1, q0))
        || (d4 == 0.0 && within(p0, p1, q1))
}

/// The bonds of a dynamic run that break: their coefficients while they hold (zero once
/// broken), which free nodes had a bond at the critical stretch at the last force
/// evaluation, and what breaking released.
pub struct Breaking {
    /// `s0`, or infinity when only pre-cracks are given.
    pub critical_stretch: f64,
    /// Read by every force evaluation (one lock per evaluation, plain loads in the bond
    /// loop), written after the steps in which bonds break.
    live: RwLock<Live>,
    /// The live bonds at the critical stretch at the last force evaluation, with what
    /// the loop read of them and where it evaluated (cleared as each evaluation starts).
    reached: Mutex<Reached>,
    /// Bonds broken since the start (both directions counted), and the elastic energy
    /// they held when they broke (J per unit thickness).
    released: Mutex<(usize, f64)>,
    /// Bonds broken from the start by the pre-cracks (both directions counted).
    pub precracked: usize,
}

/// What the last force evaluation flagged, and where it evaluated: `(t, the address of
/// the displacements)`.
#[derive(Default)]
struct Reached {
    bonds: Vec<Flagged>,
    at: Option<(f64, usize)>,
}

/// The bonds as they stand: per bond of the families, its coefficient `c_ij` (zero once
/// broken) and whether it is broken.
pub struct Live {
    /// `c_ij`, zero once broken.
    pub coefficients: Vec<f64>,
    broken: Vec<bool>,
}

impl Breaking {
    /// The bonds of `families` (over the nodes at `positions`) with their
    /// `coefficients`, those `cuts` cuts broken, breaking at `critical_stretch`
    /// (infinity: never).
    pub fn new(positions: &[Point], families: &Families, coefficients: &[f64], cuts: &Cuts, critical_stretch: f64) -> Self {
        let x = positions;
        let broken: Vec<bool> = (0..families.len())
            .into_par_iter()
            .flat_map_iter(|i| families.of(i).iter().map(move |&j| cuts.cut(x[i], x[j as usize])))
            .collect();
        let precracked = broken.iter().filter(|&&b| b).count();
        let live_coefficients: Vec<f64> = coefficients.iter().zip(&broken).map(|(&c, &cut)| if cut { 0.0 } else { c }).collect();
        let reached = Mutex::new(Reached::default());
        Breaking {
            critical_stretch,
            live: RwLock::new(Live { coefficients: live_coefficients, broken }),
            reached,
            released: Mutex::new((0, 0.0)),
            precracked,
        }
    }

    /// The bonds as they stand (held for one force evaluation).
    pub fn live(&self) -> RwLockReadGuard<'_, Live> {
        self.live.read().expect("no panic holds it")
    }

    /// Forget the bonds the previous force evaluation found at the critical stretch
    /// (called as an evaluation starts).
    pub fn start_evaluation(&self) {
        *self.reached.lock().expect("no panic holds it") = Reached::default();
    }

    /// Record the bonds `found` at the critical stretch by the evaluation at time `t` of
    /// the displacements `u` (in node and bond order).
    pub fn record(&self, found: Vec<Flagged>, t: f64, u: &[f64]) {
        debug_assert!(found.windows(2).all(|w| (w[0].node, w[0].bond) < (w[1].node, w[1].bond)));
        *self.reached.lock().expect("no panic holds it") = Reached { bonds: found, at: Some((t, u.as_ptr() as usize)) };
    }

    /// The bonds the last evaluation found at the critical stretch, in node and bond
    /// order, and whether it evaluated the displacements `u` at time `t` (then what it read
    /// of them holds at that state).
    pub fn candidates(&self, t: f64, u: &[f64]) -> (Vec<Flagged>, bool) {
        let reached = std::mem::take(&mut *self.reached.lock().expect("no panic holds it"));
        let fresh = reached.at == Some((t, u.as_ptr() as usize));
        (reached.bonds, fresh)
    }

    /// Break, in the order given, each bond of `candidates` (those of the last force
    /// evaluation, their coefficients as it read them: nothing writes them between an
    /// evaluation and the breaking after it) that `breaks(candidate)` breaks: it returns
    /// the energy the bond released and how many bond directions that counts (two
    /// where the force loop visits a pair once, `pairs::Pairs`). The bond directions
    /// broken and the energy released by this call.
    ///
    /// Only the candidates' own bonds are marked: where the loop visits each pair once
    /// from its lower node, the pair's state is that bond's (the reverse bond keeps its
    /// state from the start, and [`Breaking::damage`] reads the pair); where it visits
    /// every bond from both ends, both ends are flagged at once (the stretch is the same
    /// to the bit from either end) and each breaks on its own. The marking only writes:
    /// the candidates are scattered over the bonds, and a read of each would wait for
    /// memory.
    pub fn break_each(&self, candidates: &[Flagged], mut breaks: impl FnMut(&Flagged) -> Option<(f64, usize)>) -> (usize, f64) {
        let (mut count, mut energy) = (0, 0.0);
        {
            let mut live = self.live.write().expect("no panic holds it");
            let Live { coefficients, broken } = &mut *live;
            for f in candidates {
                debug_assert!(!broken[f.bond] && coefficients[f.bond] == f.coefficient && f.coefficient != 0.0);
                if let Some((w, n)) = breaks(f) {
                    (broken[f.bond], coefficients[f.bond]) = (true, 0.0);
                    count += n;
                    energy += w;
                }
            }
        }
        let mut r = self.released.lock().expect("no panic holds it");
        r.0 += count;
        r.1 += energy;
        (count, energy)
    }

    /// `(bonds broken since the start, energy they released)`.
    pub fn released(&self) -> (usize, f64) {
        *self.released.lock().expect("no panic holds it")
    }

    /// Damage of every free node: the share of its family's volume behind broken bonds,
    /// `phi_i = sum_{j broken} V_j / sum_j V_j` (0 intact, 1 detached). With `visited`
    /// (the bonds the force loop visits from each node when it visits each pair once,
    /// `pairs::Pairs::upper`) a pair is broken when its visited bond is
    /// ([`Breaking::break_each`]); without, each bond is read from its own end.
    pub fn damage(&self, volumes: &[f64], families: &Families, visited: Option<&(dyn Fn(usize) -> Range<usize> + Sync)>) -> Vec<f64> {
        let live = self.live();
        let free = families.len();
        let family: Vec<f64> = (0..free).into_par_iter().map(|i| families.of(i).iter().map(|&j| volumes[j as usize]).sum()).collect();
        let lost: Vec<f64> = match visited {
            None => (0..free)
                .into_par_iter()
                .map(|i| families.range(i).zip(families.of(i)).filter(|&(b, _)| live.broken[b]).map(|(_, &j)| volumes[j as usize]).sum())
                .collect(),
            Some(visited) => {
                // Each broken pair counted at both ends, from its visited bond; one buffer
                // per contiguous range of nodes, summed.
                let chunk = free.div_ceil(rayon::current_num_threads().max(1)).max(1);
                let parts: Vec<Vec<f64>> = (0..free)
                    .step_by(chunk)
                    .collect::<Vec<_>>()
                    .into_par_iter()
                    .map(|start| {
                        let mut lost = vec![0.0; free];
                        for i in start..(start + chunk).min(free) {
                            for b in visited(i).filter(|&b| live.broken[b]) {
                                let j = families.neighbour(b) as usize;
                                lost[i] += volumes[j];
                                if j < free {
                                    lost[j] += volumes[i];
                                }
                            }
                        }
                        lost
                    })
                    .collect();
                (0..free).into_par_iter().map(|i| parts.iter().map(|p| p[i]).sum()).collect()
            }
        };
        family.iter().zip(&lost).map(|(&all, &lost)| if all > 0.0 { lost / all } else { 0.0 }).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_cross_as_drawn() {
        assert!(segments_cross([0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 0.0]));
        assert!(!segments_cross([0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]));
        // Ending on the crack counts; passing its end does not.
        assert!(segments_cross([0.0, 0.0], [0.5, 0.0], [0.5, -1.0], [0.5, 1.0]));
        assert!(!segments_cross([0.0, 2.0], [1.0, 2.0], [0.5, -1.0], [0.5, 1.0]));
    }

    /// Ha and Bobaru's plane-strain relation for the plain kernel at nu = 1/4:
    /// `c = 48 E / (5 pi delta^3)` and `s0 = sqrt(5 pi G0 / (12 E delta))`.
    #[test]
    fn the_plain_kernel_gives_ha_and_bobaru() {
        let (e, delta, g0): (f64, f64, f64) = (72e9, 1.5e-3, 300.0);
        let c = 48.0 * e / (5.0 * std::f64::consts::PI * delta.powi(3));
        let m = Micromodulus { kernel: Kernel::Plain, horizon: delta, constant: c };
        let f = Fracture::new(Some(CriticalStretch::EnergyReleaseRate(g0)), &[]).unwrap();
        let want = (5.0 * std::f64::consts::PI * g0 / (12.0 * e * delta)).sqrt();
        let got = f.critical_stretch(&m).unwrap();
        assert!((got - want).abs() < 1e-12 * want, "{got} {want}");
    }
}
