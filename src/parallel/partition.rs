//! Partition of a point set over MPI ranks ([`super::distributed`]): points ordered along a Morton
//! (Z-order) curve of their positions and cut into runs of equal length, so that each
//! rank owns a compact patch and its stencils reach few points of other ranks.

/// A position `[x, y]`.
type Point = [f64; 2];

/// Bits per axis of the Morton key (the bounding box cut into `2^21 x 2^21` cells).
const BITS: u32 = 21;

/// `v`'s bits spread to the even positions of a `u64`.
fn spread(v: u64) -> u64 {
    let mut x = v & ((1 << BITS) - 1);
    x = (x | (x << 16)) & 0x0000_ffff_0000_ffff;
    x = (x | (x << 8)) & 0x00ff_00ff_00ff_00ff;
    x = (x | (x << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
    x = (x | (x << 2)) & 0x3333_3333_3333_3333;
    (x | (x << 1)) & 0x5555_5555_5555_5555
}

/// Owner rank of each point: the points sorted by Morton key of their position in
/// the bounding box (ties by index, so the partition does not depend on round-off
/// order), then `ranks` consecutive runs whose lengths differ by at most one.
pub fn morton_owners(points: &[Point], ranks: usize) -> Vec<u32> {
    let n = points.len();
    if ranks <= 1 || n == 0 {
        return vec![0; n];
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let cells = ((1u64 << BITS) - 1) as f64;
    let cell = |p: &Point, d: usize| {
        let w = hi[d] - lo[d];
        if w > 0.0 {
            ((p[d] - lo[d]) / w * cells) as u64
        } else {
            0
        }
    };
    let mut order: Vec<(u64, usize)> =
        points.iter().enumerate().map(|(i, p)| (spread(cell(p, 0)) | (spread(cell(p, 1)) << 1), i)).collect();
    order.sort_unstable();
    let mut owner = vec![0u32; n];
    for (k, &(_, i)) in order.iter().enumerate() {
        owner[i] = (k * ranks / n) as u32;
    }
    owner
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a 40 x 40 grid split in four, each rank gets 400 points, and its points form
    /// a compact patch: the Z-curve's first quarter is the lower-left quadrant.
    #[test]
    fn four_ranks_get_the_four_quadrants_of_a_square_grid() {
        let points: Vec<Point> = (0..1600).map(|k| [(k % 40) as f64, (k / 40) as f64]).collect();
        let owner = morton_owners(&points, 4);
        for r in 0..4u32 {
            assert_eq!(owner.iter().filter(|&&o| o == r).count(), 400, "rank {r}");
        }
        for (p, &o) in points.iter().zip(&owner) {
            let quadrant = (p[0] >= 20.0) as u32 + 2 * (p[1] >= 20.0) as u32;
            assert_eq!(o, quadrant, "point {p:?}");
        }
        assert!(morton_owners(&points, 1).iter().all(|&o| o == 0));
    }
}
