fn main() {
    let args: Vec<String> = std::env::args().collect();
    let p = mlsm::problem::Problem::from_file(std::path::Path::new(&args[1])).unwrap();
    let p = p.with_spacing(args[2].parse().unwrap());
    let s = mlsm::run::solve(&p, &mlsm::run::Silent).unwrap();
    let (_, se) = s.exact.as_ref().unwrap();
    let (sh, _, _) = s.stress.as_ref().unwrap();
    let smax = se.iter().flat_map(|s| s.iter().map(|v| v.abs())).fold(0.0, f64::max);
    let mut errs: Vec<(f64, usize)> = (0..s.nodes.len()).map(|i| ((0..3).map(|k| (sh[i][k]-se[i][k]).abs()).fold(0.0, f64::max)/smax, i)).collect();
    errs.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
    for &(e, i) in errs.iter().take(8) {
        let b = if i < s.nodes.boundary.len() { format!("{:?}", s.nodes.boundary[i].touches) } else { "interior".into() };
        println!("{e:.3e} node {i} {:?} {b}", s.nodes.positions[i]);
    }
    let (ue, _) = s.exact.as_ref().unwrap();
    let mut eu: Vec<(f64, usize)> = (0..s.nodes.len()).map(|i| ((s.displacement[i][0]-ue[i][0]).abs().max((s.displacement[i][1]-ue[i][1]).abs()), i)).collect();
    eu.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
    for &(e, i) in eu.iter().take(5) {
        let b = if i < s.nodes.boundary.len() { format!("{:?}", s.nodes.boundary[i].touches) } else { "interior".into() };
        println!("u err {e:.3e} node {i} {:?} {b}", s.nodes.positions[i]);
    }
    println!("e_inf_u {:?}", s.errors);
}
