#!/bin/sh
# Installs the Debian 12 packages the solver and its Python post-processing need.
set -e
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends \
  build-essential pkg-config petsc-dev libgmsh-dev libhdf5-openmpi-dev libmetis-dev libyaml-dev libopenblas0 \
  openmpi-bin libopenmpi-dev python3 python3-h5py python3-numpy python3-matplotlib python3-yaml python3-gmsh python3-getfem python3-dolfinx python3-pytest python3-pytest-xdist python3-hypothesis paraview python3-paraview
