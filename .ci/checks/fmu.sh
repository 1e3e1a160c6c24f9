#!/usr/bin/env bash
# The FMU and the exported controller checked by independent tools:
#  - FMPy (PyPI `fmpy`) validates the FMU, runs it against `seat-twin simulate`, saves and
#    restores its state, closes the loop outside (tests/fmu/check_fmu.py);
#  - python-control's `sample_system` checks the discretised controller's coefficients
#    (tests/fmu/check_controller.py).
# Installs them into a virtual environment under the cargo target directory (once; a second
# run installs nothing), builds the binary and the FMU's shared library, runs the checks.
set -euo pipefail
cd "$(dirname "$0")/../.."

# Absolute: FMPy makes a file URI of the unpacked FMU's folder.
target=$(realpath -m "${CARGO_TARGET_DIR:-target}")
venv="$target/fmu-venv"
# Pinned: the versions the checks were written against.
packages=(fmpy==0.3.32 control==0.10.2)

if ! "$venv/bin/python" - "${packages[@]}" <<'PY' 2>/dev/null
import sys
from importlib.metadata import version
for spec in sys.argv[1:]:
    name, want = spec.split("==")
    if version(name) != want:
        sys.exit(1)
PY
then
    echo "installing ${packages[*]} into $venv"
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check "${packages[@]}" || {
        echo "error: could not install ${packages[*]} from PyPI into $venv" >&2
        exit 1
    }
fi

# The same build as the test command's (features as there): the binary and, beside it,
# libseat_twin.so, which `export fmu` packs. `--examples` is not for the examples: a build
# that includes them resolves features with the dev-dependencies, as `cargo test` does, so
# right after the test command nothing is compiled; without it the library and the GUI stack
# are compiled again (2 min 15 s here), and once more back by the web check.
features="${SEAT_TWIN_FEATURES:---all-features}"
cargo build $features --bin seat-twin --lib --examples --quiet
exe="$target/debug/seat-twin"

work="$target/fmu-check"
rm -rf "$work"
mkdir -p "$work"
"$venv/bin/python" tests/fmu/check_fmu.py "$exe" "$work"
"$venv/bin/python" tests/fmu/check_controller.py "$exe" "$work"
