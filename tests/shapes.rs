//! Shape functions reproduce every polynomial up to the basis degree, for every
//! operator, on scattered supports, at any length scale (property test).

use mlsm::mlsm::basis::{monomial_exponents, Basis, Weight};
use mlsm::mlsm::fit::shape_functions;
use mlsm::mlsm::Op;
use mlsm::mlsm::Radial;
use proptest::prelude::*;

/// `d^(a+b)/dx^a dy^b` of `x^i y^j` at `p`.
fn monomial_derivative(i: u32, j: u32, (a, b): (u32, u32), p: [f64; 2]) -> f64 {
    if a > i || b > j {
        return 0.0;
    }
    let fall = |n: u32, k: u32| (0..k).map(|t| (n - t) as f64).product::<f64>();
    fall(i, a) * fall(j, b) * p[0].powi((i - a) as i32) * p[1].powi((j - b) as i32)
}

fn support(centre: [f64; 2], h: f64, offsets: &[(f64, f64)]) -> Vec<[f64; 2]> {
    let mut pts = vec![centre];
    pts.extend(offsets.iter().map(|(r, t)| [centre[0] + h * r * t.cos(), centre[1] + h * r * t.sin()]));
    pts
}

fn check_reproduction(
    basis: Basis,
    weight: Weight,
    centre: [f64; 2],
    h: f64,
    offsets: &[(f64, f64)],
    coeffs: &[f64],
) -> Result<(), TestCaseError> {
    let pts = support(centre, h, offsets);
    let n = pts.len();
    let ops = Op::ALL;
    let mut phi = vec![0.0; ops.len() * n];
    shape_functions(&basis, &weight, centre, &pts, &ops, &mut phi).map_err(|e| TestCaseError::reject(format!("{e:?}")))?;
    let exps = monomial_exponents(&basis);
    // Polynomial in coordinates relative to the centre and scaled by h, so that the
    // coefficients are O(1) at every length scale.
    let poly = |p: [f64; 2], op: Op| -> f64 {
        let z = [(p[0] - centre[0]) / h, (p[1] - centre[1]) / h];
        let (a, b) = op.multi_index();
        exps.iter().zip(coeffs).map(|(&(i, j), c)| c * monomial_derivative(i, j, (a, b), z)).sum::<f64>() / h.powi((a + b) as i32)
    };
    for (k, &op) in ops.iter().enumerate() {
        let approx: f64 = (0..n).map(|j| phi[k * n + j] * poly(pts[j], Op::Value)).sum();
        let exact = poly(centre, op);
        // Each shape weight is ~ 1/h^order; round-off in the local QR (condition
        // number <= ~1e4 for these supports) times the sum of |phi_j u_j| bounds the error.
        let scale: f64 = (0..n).map(|j| (phi[k * n + j] * poly(pts[j], Op::Value)).abs()).sum::<f64>().max(1.0 / h.powi(op.order()));
        prop_assert!((approx - exact).abs() <= 1e-9 * scale, "{basis:?} {op:?} h={h:e}: {approx} vs {exact} (scale {scale:e})");
    }
    Ok(())
}

/// Scattered offsets (radius in units of h, angle) of a support of `n - 1` neighbours:
/// one neighbour per angular sector with jittered radius, so supports are never degenerate.
fn offsets(n: usize) -> impl Strategy<Value = Vec<(f64, f64)>> {
    prop::collection::vec((0.7f64..2.2, 0.0f64..0.8), n - 1).prop_map(move |v| {
        let m = v.len() as f64;
        v.into_iter()
            .enumerate()
            .map(|(k, (r, t))| (r * (1.0 + (k % 3) as f64 * 0.3), (k as f64 + t) * std::f64::consts::TAU / m))
            .collect()
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, .. ProptestConfig::default() })]

    #[test]
    fn monomials_degree_2_reproduce_quadratics(off in offsets(12), c in prop::collection::vec(-1.0f64..1.0, 6), e in -3i32..4, cx in -5.0f64..5.0) {
        let h = 10f64.powi(e);
        check_reproduction(Basis::Monomials { degree: 2 }, Weight::Gaussian { sigma: 1.0 }, [cx * h, 2.0 * h], h, &off, &c)?;
    }

    #[test]
    fn monomials_degree_3_reproduce_cubics(off in offsets(20), c in prop::collection::vec(-1.0f64..1.0, 10), e in -3i32..4) {
        let h = 10f64.powi(e);
        check_reproduction(Basis::Monomials { degree: 3 }, Weight::Gaussian { sigma: 1.5 }, [h, -h], h, &off, &c)?;
    }

    #[test]
    fn monomials_degree_4_reproduce_quartics(off in offsets(30), c in prop::collection::vec(-1.0f64..1.0, 15)) {
        check_reproduction(Basis::Monomials { degree: 4 }, Weight::None, [0.3, 0.7], 0.01, &off, &c)?;
    }

    #[test]
    fn phs_reproduces_polynomials_up_to_its_degree(
        degree in 2u32..7,
        order in prop::sample::select(vec![3u32, 5, 7]),
        off in offsets(60),
        c in prop::collection::vec(-1.0f64..1.0, 28),
        e in -3i32..4,
    ) {
        prop_assume!(degree >= (order - 1) / 2);
        let n = 2 * ((degree + 1) * (degree + 2) / 2) as usize;
        let basis = Basis::RbfFd { radial: Radial::Phs { order }, degree };
        let m = monomial_exponents(&basis).len();
        check_reproduction(basis, Weight::None, [0.5, -0.25], 10f64.powi(e), &off[..n - 1], &c[..m])?;
    }

    #[test]
    fn shape_parameter_rbf_fd_reproduces_quadratics(off in offsets(12), c in prop::collection::vec(-1.0f64..1.0, 6), shape in 1.0f64..4.0) {
        for radial in [Radial::Gaussian { shape }, Radial::Mq { shape }, Radial::Imq { shape }] {
            check_reproduction(Basis::RbfFd { radial, degree: 2 }, Weight::None, [2.0, 1.0], 0.1, &off, &c)?;
        }
    }

    #[test]
    fn tensor_degree_2_reproduces_biquadratics(off in offsets(16), c in prop::collection::vec(-1.0f64..1.0, 9), e in -2i32..3) {
        let h = 10f64.powi(e);
        check_reproduction(Basis::Tensor { degree: 2 }, Weight::Gaussian { sigma: 1.0 }, [0.0, 0.0], h, &off, &c)?;
    }
}

#[test]
fn rbf_fd_interpolates() {
    // RBF-FD interpolates on its stencil: the value weights at the centre (a stencil
    // node) are the unit vector, for every radial function.
    let pts = support([1.0, 1.0], 0.1, &[(1.0, 0.1), (1.1, 1.3), (0.9, 2.5), (1.2, 3.3), (1.0, 4.4), (1.3, 5.5), (1.6, 0.7), (1.7, 3.9)]);
    for radial in [
        Radial::Phs { order: 3 },
        Radial::Phs { order: 5 },
        Radial::Gaussian { shape: 2.0 },
        Radial::Mq { shape: 2.0 },
        Radial::Imq { shape: 2.0 },
    ] {
        let mut phi = vec![0.0; pts.len()];
        shape_functions(&Basis::RbfFd { radial, degree: 2 }, &Weight::None, [1.0, 1.0], &pts, &[Op::Value], &mut phi).unwrap();
        assert!((phi[0] - 1.0).abs() < 1e-10, "{radial:?}: {phi:?}");
        assert!(phi[1..].iter().all(|v| v.abs() < 1e-10), "{radial:?}: {phi:?}");
    }
}

#[test]
fn collinear_support_is_reported_not_nan() {
    let pts: Vec<[f64; 2]> = (0..9).map(|k| [k as f64 * 0.1, 0.0]).collect();
    let mut phi = vec![0.0; 9];
    let r = shape_functions(&Basis::Monomials { degree: 2 }, &Weight::None, pts[0], &pts, &[Op::Dxx], &mut phi);
    assert!(r.is_err());
}

/// RBF-FD solves reuse one thread's buffers from stencil to stencil (`mlsm::rbffd`):
/// a stencil's weights are the same, to the bit, whatever the thread solved before it:
/// another stencil of the same size (its factors left in the buffer), and stencils of
/// other sizes and degrees.
#[test]
fn rbf_fd_weights_do_not_depend_on_the_stencils_solved_before() {
    let ring =
        |twist: f64| -> Vec<(f64, f64)> { (1..80).map(|k| (1.0 + 0.37 * (k % 7) as f64 + 0.05 * k as f64, twist * k as f64)).collect() };
    let ops = [Op::Dx, Op::Dy, Op::Dxx, Op::Dxy, Op::Dyy];
    let weights = |degree: u32, n: usize, twist: f64| {
        let pts = support([0.5, -0.25], 0.1, &ring(twist)[..n - 1]);
        let mut w = vec![0.0; ops.len() * n];
        let basis = Basis::RbfFd { radial: Radial::Phs { order: 3 }, degree };
        shape_functions(&basis, &Weight::None, [0.5, -0.25], &pts, &ops, &mut w).unwrap();
        w
    };
    let first = weights(4, 30, 2.399);
    let other = weights(4, 30, 1.1);
    assert_ne!(other, first, "a different stencil of the same size");
    assert_eq!(weights(4, 30, 2.399), first);
    let _ = weights(2, 12, 1.1);
    let _ = weights(6, 56, 1.1);
    assert_eq!(weights(4, 30, 2.399), first);
}
