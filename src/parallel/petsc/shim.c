/* The C side of mlsm's PETSc backend (src/parallel/petsc/mod.rs): a handful of functions with
 * plain C types, so that no MPI or PETSc type crosses into Rust. Every function
 * returns PETSc's error code (0 = success); PETSc prints its own trace on failure. */

#include <petscksp.h>
#include <stdint.h>
#include <string.h>

static char mlsm_help[] = "mlsm: meshless 2D elasticity; PETSc options pass through after `--`.\n";

/* Start PETSc (and MPI) with the given options; `args[0]` is the program name. */
int mlsm_petsc_initialize(int argc, char **argv) {
  return (int)PetscInitialize(&argc, &argv, NULL, mlsm_help);
}

/* End PETSc (and MPI when PETSc started it). */
int mlsm_petsc_finalize(void) { return (int)PetscFinalize(); }

/* Rank of this process and number of processes in PETSC_COMM_WORLD. */
int mlsm_petsc_world(int *rank, int *size) {
  PetscMPIInt r, s;
  PetscCall(MPI_Comm_rank(PETSC_COMM_WORLD, &r));
  PetscCall(MPI_Comm_size(PETSC_COMM_WORLD, &s));
  *rank = r;
  *size = s;
  return 0;
}

/* data[k] <- sum over ranks of data[k], k < n. */
int mlsm_petsc_sum(double *data, int64_t n) {
  PetscCall(MPI_Allreduce(MPI_IN_PLACE, data, (int)n, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD));
  return 0;
}

/* Every rank's `local` (counts[r] values on rank r) concatenated by rank into `all`. */
int mlsm_petsc_gather(const double *local, const int64_t *counts, double *all) {
  PetscMPIInt size;
  PetscCall(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  int *c, *d;
  PetscCall(PetscMalloc2(size, &c, size, &d));
  int offset = 0;
  for (int r = 0; r < size; ++r) {
    c[r] = (int)counts[r];
    d[r] = offset;
    offset += c[r];
  }
  PetscMPIInt rank;
  PetscCall(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  PetscCall(MPI_Allgatherv(local, c[rank], MPI_DOUBLE, all, c, d, MPI_DOUBLE, PETSC_COMM_WORLD));
  PetscCall(PetscFree2(c, d));
  return 0;
}

/* This rank's rows of a distributed square system, in CSR with global column indices. */
typedef struct {
  int64_t global_rows;     /* rows of the whole system */
  int64_t local_rows;      /* rows owned here: global rows first_row .. first_row + local_rows */
  const int64_t *row_ptr;  /* local_rows + 1 offsets into cols / vals */
  const int64_t *cols;     /* sorted global columns of each row */
  const double *vals;
  const double *rhs;       /* local_rows values */
  int64_t block_size;      /* unknowns per point (2 or 3) */
  const double *coords;    /* local_rows / block_size points (x, y), or NULL: rigid-body modes for GAMG */
  double rtol;             /* default relative tolerance */
  int64_t max_it;          /* default iteration limit */
  int64_t restart;         /* default GMRES restart */
  const char *ksp_type;    /* default Krylov method */
  const char *pc_type;     /* default preconditioner */
  const char *factor_package; /* default factorisation package of pc lu ("" = PETSc's) */
} mlsm_system;

/* What the solve did: the options database may have changed every default. */
typedef struct {
  int64_t iterations;
  int64_t reason;          /* KSPConvergedReason: > 0 converged, < 0 diverged */
  double rtol;             /* the relative tolerance in force */
  int64_t max_it;          /* the iteration limit in force */
  double setup_seconds;
  double solve_seconds;
  char reason_name[64];
  char ksp_type[32];
  char pc_type[32];
} mlsm_outcome;

/* Solve the system with KSP; x receives this rank's local_rows values. */
int mlsm_petsc_solve(const mlsm_system *s, double *x, mlsm_outcome *out) {
  Mat A;
  Vec b, u;
  KSP ksp;
  PC pc;
  PetscInt n = (PetscInt)s->local_rows;
  PetscInt *ia, *ja;
  PetscInt nnz = (PetscInt)s->row_ptr[s->local_rows];
  PetscLogDouble t0, t1, t2;

  PetscCall(PetscMalloc2(n + 1, &ia, nnz, &ja));
  for (PetscInt i = 0; i <= n; ++i) ia[i] = (PetscInt)s->row_ptr[i];
  for (PetscInt k = 0; k < nnz; ++k) ja[k] = (PetscInt)s->cols[k];
  PetscCall(PetscTime(&t0));
  PetscCall(MatCreate(PETSC_COMM_WORLD, &A));
  PetscCall(MatSetSizes(A, n, n, (PetscInt)s->global_rows, (PetscInt)s->global_rows));
  PetscCall(MatSetType(A, MATAIJ));
  PetscCall(MatSetBlockSize(A, (PetscInt)s->block_size));
  PetscCall(MatSetFromOptions(A));
  PetscCall(MatSeqAIJSetPreallocationCSR(A, ia, ja, s->vals));
  PetscCall(MatMPIAIJSetPreallocationCSR(A, ia, ja, s->vals));
  PetscCall(PetscFree2(ia, ja));

  PetscCall(MatCreateVecs(A, &u, &b));
  {
    PetscScalar *bv;
    PetscCall(VecGetArray(b, &bv));
    for (PetscInt i = 0; i < n; ++i) bv[i] = s->rhs[i];
    PetscCall(VecRestoreArray(b, &bv));
  }
  if (s->coords) {
    Vec c;
    MatNullSpace rigid;
    PetscScalar *cv;
    PetscCall(VecCreateMPI(PETSC_COMM_WORLD, 2 * (n / s->block_size), PETSC_DECIDE, &c));
    PetscCall(VecSetBlockSize(c, 2));
    PetscCall(VecGetArray(c, &cv));
    for (PetscInt i = 0; i < 2 * (n / s->block_size); ++i) cv[i] = s->coords[i];
    PetscCall(VecRestoreArray(c, &cv));
    PetscCall(MatNullSpaceCreateRigidBody(c, &rigid));
    PetscCall(MatSetNearNullSpace(A, rigid));
    PetscCall(MatNullSpaceDestroy(&rigid));
    PetscCall(VecDestroy(&c));
  }

  PetscCall(KSPCreate(PETSC_COMM_WORLD, &ksp));
  PetscCall(KSPSetOperators(ksp, A, A));
  PetscCall(KSPSetType(ksp, s->ksp_type));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, s->pc_type));
  if (s->factor_package[0]) PetscCall(PCFactorSetMatSolverType(pc, s->factor_package));
  /* Right preconditioning with the unpreconditioned norm: the tolerance then bounds
     the true residual, as for mlsm's own Krylov solvers. */
  PetscCall(KSPSetPCSide(ksp, PC_RIGHT));
  PetscCall(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED));
  PetscCall(KSPSetTolerances(ksp, s->rtol, 0.0, PETSC_DEFAULT, (PetscInt)s->max_it));
  PetscCall(KSPGMRESSetRestart(ksp, (PetscInt)s->restart));
  PetscCall(KSPSetFromOptions(ksp));
  PetscCall(KSPSetUp(ksp));
  PetscCall(PetscTime(&t1));
  PetscCall(KSPSolve(ksp, b, u));
  PetscCall(PetscTime(&t2));

  {
    PetscInt its, maxit;
    PetscReal rtol, abstol, dtol;
    KSPConvergedReason reason;
    KSPType kt;
    PCType pt;
    const char *rn;
    PetscCall(KSPGetIterationNumber(ksp, &its));
    PetscCall(KSPGetConvergedReason(ksp, &reason));
    PetscCall(KSPGetConvergedReasonString(ksp, &rn));
    PetscCall(KSPGetTolerances(ksp, &rtol, &abstol, &dtol, &maxit));
    PetscCall(KSPGetType(ksp, &kt));
    PetscCall(PCGetType(pc, &pt));
    out->iterations = its;
    out->reason = (int64_t)reason;
    out->rtol = rtol;
    out->max_it = maxit;
    out->setup_seconds = t1 - t0;
    out->solve_seconds = t2 - t1;
    PetscCall(PetscStrncpy(out->reason_name, rn ? rn : "?", sizeof(out->reason_name)));
    PetscCall(PetscStrncpy(out->ksp_type, kt ? kt : "?", sizeof(out->ksp_type)));
    PetscCall(PetscStrncpy(out->pc_type, pt ? pt : "?", sizeof(out->pc_type)));
  }
  {
    const PetscScalar *uv;
    PetscCall(VecGetArrayRead(u, &uv));
    for (PetscInt i = 0; i < n; ++i) x[i] = uv[i];
    PetscCall(VecRestoreArrayRead(u, &uv));
  }
  PetscCall(KSPDestroy(&ksp));
  PetscCall(VecDestroy(&u));
  PetscCall(VecDestroy(&b));
  PetscCall(MatDestroy(&A));
  return 0;
}
