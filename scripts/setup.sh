#!/bin/sh
# One idempotent setup for a fresh Debian 12 (bookworm) machine, as root:
#   1. the Debian packages of the FEniCSx stack, a C compiler for dolfinx's
#      form JIT, OpenMPI, an off-screen OpenGL stack for pyvista, chromium
#      for the report's browser test;
#   2. a virtual environment .venv from /usr/bin/python3 that sees those
#      packages (--system-site-packages), with numpy held at Debian's build;
#   3. the project in editable mode, with its pinned PyPI dependencies.
# A second run with nothing to do is a few dpkg queries and one hash check.
# The README (through make), .ci/run and docker/Dockerfile all call this file.
set -eu

here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
venv=${UPD_VENV:-$here/.venv}

DEBS="python3-dolfinx python3-petsc4py python3-slepc4py python3-mpi4py \
python3-gmsh python3-h5py python3-meshio python3-scipy python3-venv python3-dev \
python3-pip openmpi-bin libopenmpi-dev build-essential pkg-config \
libopenblas0-pthread \
libx11-6 libxrender1 libxext6 libgl1 libegl1 libegl-mesa0 libgl1-mesa-dri libglu1-mesa \
chromium fonts-dejavu-core ca-certificates"

missing=""
for p in $DEBS; do
    s=$(dpkg-query -W -f='${db:Status-Abbrev}' "$p" 2>/dev/null || true)
    case "$s" in ii*) ;; *) missing="$missing $p" ;; esac
done
if [ -n "$missing" ]; then
    echo "setup: installing Debian packages:$missing" >&2
    if [ "$(id -u)" -ne 0 ]; then
        if command -v sudo >/dev/null 2>&1; then SUDO=sudo; else
            echo "setup: these Debian packages are missing and this is not root (no sudo):$missing" >&2
            exit 2
        fi
    else SUDO=""; fi
    export DEBIAN_FRONTEND=noninteractive
    $SUDO apt-get update -q
    # shellcheck disable=SC2086
    $SUDO apt-get install -y -q --no-install-recommends $missing
fi

# MPI starts take 5 s longer when the host name does not resolve.
if ! getent hosts "$(hostname)" >/dev/null 2>&1 && [ -w /etc/hosts ]; then
    echo "127.0.1.1 $(hostname)" >>/etc/hosts
fi

if [ ! -x "$venv/bin/python" ]; then
    echo "setup: creating $venv (system site packages)" >&2
    /usr/bin/python3 -m venv --system-site-packages "$venv"
fi

# Reinstall the Python side only when what it depends on changed.
stamp="$venv/.upd-setup-stamp"
want=$(cat pyproject.toml scripts/constraints.txt scripts/setup.sh | sha256sum | cut -c1-16)
if [ "$(cat "$stamp" 2>/dev/null || true)" != "$want" ]; then
    echo "setup: installing Python packages into $venv" >&2
    export PIP_DISABLE_PIP_VERSION_CHECK=1
    "$venv/bin/python" -m pip install -q -c scripts/constraints.txt -e ".[dev]"
    "$venv/bin/python" - <<'PY'
import numpy, dolfinx, petsc4py, slepc4py, gmsh, h5py, pyvista, vtk, matplotlib
assert numpy.__version__ == "1.24.2", f"numpy {numpy.__version__} replaced Debian's 1.24.2"
print(f"setup: dolfinx {dolfinx.__version__}, numpy {numpy.__version__}, "
      f"vtk {vtk.vtkVersion.GetVTKVersion()}, pyvista {pyvista.__version__}")
PY
    echo "$want" >"$stamp"
fi
# OpenBLAS's kernels: Debian's OpenBLAS falls back to generic (SSE3) kernels on a CPU newer
# than itself, 3-7 times slower on dense algebra; a start-up hook in the venv then picks the
# right ones (OPENBLAS_CORETYPE). Checked on every run: the venv may have moved machine.
"$venv/bin/python" scripts/openblas_core.py "$venv"
# the compiled small-system corrector, built ahead of time so that small runs (upd frf) load
# it without numba; a no-op when it is up to date (a digest of its sources), about 3 min when not
if ! "$venv/bin/python" -m workbench.hbm.forced.small_aot; then
    echo "setup: the ahead-of-time kernels were not built; numba compiles them at first use" >&2
fi
echo "setup: ready ($venv)" >&2
