//! With the cargo feature `petsc`: compile the C side of the PETSc backend
//! (`src/parallel/petsc/shim.c`) against the PETSc and Open MPI found by pkg-config (Debian's
//! `petsc-dev` and `libopenmpi-dev`; `scripts/install-petsc.sh`). Without it: nothing.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    #[cfg(feature = "petsc")]
    petsc();
}

#[cfg(feature = "petsc")]
fn petsc() {
    println!("cargo:rerun-if-changed=src/parallel/petsc/shim.c");
    let found = |name: &str| {
        pkg_config::Config::new()
            .probe(name)
            .unwrap_or_else(|e| panic!("the `petsc` feature needs {name} from pkg-config ({e}); run scripts/install-petsc.sh"))
    };
    let petsc = found("PETSc");
    let mpi = found("ompi-c");
    let mut build = cc::Build::new();
    build.file("src/parallel/petsc/shim.c").warnings(true);
    for dir in petsc.include_paths.iter().chain(&mpi.include_paths) {
        build.include(dir);
    }
    build.compile("mlsm_petsc_shim");
    // The shim's symbols come first; the libraries it calls follow it on the link line.
    for lib in petsc.libs.iter().chain(&mpi.libs) {
        println!("cargo:rustc-link-lib={lib}");
    }
}
