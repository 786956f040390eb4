//! What graded node density buys: the Flamant line load (problems/flamant.toml), whose
//! stresses vary on the scale of the distance r to the load, solved on the shipped
//! graded node set (h = 0.0005 + 0.03 r, capped at 0.03) and on a uniform scattered
//! set with about the same number of nodes, same basis (PHS RBF-FD, p = 4).

mod common;
use common::*;

#[test]
fn graded_density_beats_uniform_nodes_on_the_flamant_load() {
    let (n_graded, eu_graded, es_graded) = errors(&scene("flamant", &[]));
    let (n_uniform, eu_uniform, es_uniform) = errors(&scene("flamant", &[("nodes.refine", None), ("nodes.spacing", f(0.018))]));
    eprintln!("graded {n_graded} nodes: {eu_graded:.2e} / {es_graded:.2e}; uniform {n_uniform} nodes: {eu_uniform:.2e} / {es_uniform:.2e}");
    // Same budget: the node counts agree within 15 %.
    assert!((n_graded as f64 / n_uniform as f64 - 1.0).abs() < 0.15, "{n_graded} vs {n_uniform}");
    // Measured: graded 4953 nodes 1.1e-4 / 2.0e-4, uniform 4939 nodes 3.3e-3 / 6.5e-3
    // (30x); uniform sets of this size give 1e-3 .. 9e-3 in u depending on the seed
    // (seeds 1-5 at h = 0.02). A 5x margin holds for every
    // uniform set measured and fails if the grading stops working (graded towards the
    // wrong point, or with the growth too fast, gave no gain at all).
    assert!(eu_uniform > 5.0 * eu_graded, "u: graded {eu_graded:.2e}, uniform {eu_uniform:.2e}");
    assert!(es_uniform > 5.0 * es_graded, "sigma: graded {es_graded:.2e}, uniform {es_uniform:.2e}");
    // The shipped scene's accuracy, with a factor 3 over the measured values for
    // changes of the node set by the fill (the seed-to-seed spread measured above).
    assert!(eu_graded < 3.3e-4 && es_graded < 6e-4, "graded: {eu_graded:.2e} / {es_graded:.2e}");
}
