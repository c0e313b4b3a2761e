#!/usr/bin/env bash
# cota (the Python package) against pymartini and pydelatin, in one run:
# makes a venv in bench/.peers/pyenv (ignored by git) with pinned pip installs,
# builds ./crates/cota-py into it, and runs bench/python_peers.py.
#
# Usage: bench/python-peers.sh [DEM...]   (default: fixtures/S29W072.hgt.zip)
# Env:   COTA_PY_E (errors in m, default 5), COTA_PY_RUNS (default 5).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
venv="$here/.peers/pyenv"
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -m pip install -q --disable-pip-version-check \
  "maturin==1.16.0" "numpy==2.3.5" "pymartini==0.6.0" "pydelatin==0.4.0"
PATH="$venv/bin:$PATH" "$venv/bin/python" -m pip install -q --disable-pip-version-check \
  --no-build-isolation "$root/crates/cota-py"
"$venv/bin/python" "$here/python_peers.py" "$@"
