#!/usr/bin/env bash
# Runs every test of the workspace. The end-to-end printer tests also talk to a printer simulation
# the project did not write (OctoPrint's virtual printer, from PyPI): it is installed into .venv
# the first time (a minute; later runs reuse it).
set -euo pipefail
cd "$(dirname "$0")/.."
OCTOPRINT_VERSION="1.11.8"
if ! .venv/bin/python -c "import octoprint.plugins.virtual_printer.virtual" 2> /dev/null; then
  python3 -m venv .venv
  .venv/bin/pip install --quiet --disable-pip-version-check "OctoPrint==$OCTOPRINT_VERSION"
fi
export CLAYLOFT_VIRTUAL_PRINTER_PYTHON="$PWD/.venv/bin/python"
exec cargo test --release --workspace "$@"
