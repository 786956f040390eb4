//! What least squares and RBF-FD share at one centre: the stencil in local
//! coordinates `z = (x - centre) / radius`, the monomials at those points, and the
//! error of a fit whose polynomial part is rank deficient.

use super::basis::LocalBasis;

/// Why a local fit failed.
#[derive(Debug, Clone, PartialEq)]
pub struct RankDeficient {
    /// Smallest `|R_kk| / max |R_kk|` found.
    pub ratio: f64,
    /// Basis size `m`.
    pub basis_size: usize,
}

/// The monomials of `local` at the local coordinates `z`: the column-major
/// `z.len() x m` matrix `P_jk = b_k(z_j)`.
pub fn monomial_matrix(local: &LocalBasis, z: &[[f64; 2]]) -> Vec<f64> {
    let mut p = Vec::new();
    monomial_matrix_into(local, z, &mut p);
    p
}

/// [`monomial_matrix`] written to `p` (resized; a stencil loop keeps one buffer).
pub fn monomial_matrix_into(local: &LocalBasis, z: &[[f64; 2]], p: &mut Vec<f64>) {
    const MOST: usize = 136; // degree 15: (15 + 1)(15 + 2) / 2
    let (n, m) = (z.len(), local.len());
    p.resize(n * m, 0.0);
    let mut row_buffer = [0.0; MOST];
    let mut row_vec = Vec::new();
    let row: &mut [f64] = if m <= MOST {
        &mut row_buffer[..m]
    } else {
        row_vec.resize(m, 0.0);
        &mut row_vec
    };
    for (j, &zj) in z.iter().enumerate() {
        local.values(zj, row);
        for (k, &v) in row.iter().enumerate() {
            p[k * n + j] = v;
        }
    }
}

/// A stencil in local coordinates: `z_j = (x_j - centre) / radius`, `radius` the
/// largest distance from the centre, `nearest` the smallest non-zero one (the local
/// spacing that scales weights and shape parameters). Shared by least squares and
/// RBF-FD, so both are invariant to translation and to the unit of length.
#[derive(Default)]
pub struct LocalFrame {
    /// `|x_j - centre|`.
    pub dist: Vec<f64>,
    /// `max_j |x_j - centre|`.
    pub radius: f64,
    /// `min_j |x_j - centre|` over the points other than the centre.
    pub nearest: f64,
    /// Scaled local coordinates.
    pub z: Vec<[f64; 2]>,
}

impl LocalFrame {
    /// The frame of `points` around `centre`.
    pub fn new(centre: [f64; 2], points: &[[f64; 2]]) -> LocalFrame {
        let mut frame = LocalFrame::default();
        frame.fill(centre, points);
        frame
    }

    /// This frame made the frame of `points` around `centre`, in its own buffers.
    pub fn fill(&mut self, centre: [f64; 2], points: &[[f64; 2]]) {
        self.z.clear();
        self.z.extend(points.iter().map(|x| [x[0] - centre[0], x[1] - centre[1]]));
        self.dist.clear();
        self.dist.extend(self.z.iter().map(|d| d[0].hypot(d[1])));
        self.radius = self.dist.iter().cloned().fold(0.0, f64::max);
        self.nearest = self.dist.iter().cloned().filter(|&d| d > 0.0).fold(f64::INFINITY, f64::min);
        let radius = self.radius;
        self.z.iter_mut().for_each(|d| *d = [d[0] / radius, d[1] / radius]);
    }
}
