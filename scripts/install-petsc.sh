#!/usr/bin/env bash
# Install what the cargo feature `petsc` needs on a Debian 12 machine: PETSc 3.18
# (petsc-dev, with MUMPS and hypre) and Open MPI, plus pkg-config, which build.rs asks.
# Needs root (or sudo). Does nothing when everything is there already.
set -euo pipefail
if pkg-config --exists PETSc ompi-c 2>/dev/null && command -v mpirun >/dev/null; then
    echo "PETSc $(pkg-config --modversion PETSc) and Open MPI are installed"
    exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    petsc-dev libopenmpi-dev openmpi-bin pkg-config
echo "PETSc $(pkg-config --modversion PETSc) and Open MPI installed"
