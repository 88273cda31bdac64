#!/usr/bin/env bash
# The documentation site (mkdocs.yml, docs/site.md): install the docs extra, then build it
# strictly into site/ (a broken link fails the build); "serve" serves it at http://127.0.0.1:8000
# instead, rebuilt on every change.
#   bash scripts/site.sh          # site/
#   bash scripts/site.sh serve    # http://127.0.0.1:8000
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install.sh docs
export NO_MKDOCS_2_WARNING=1  # Material's notice about its successor, printed on every build
if [ "${1:-build}" = serve ]; then
  exec .venv/bin/mkdocs serve
fi
.venv/bin/mkdocs build --strict
echo "built site/: open site/index.html through a server (bash scripts/site.sh serve), not as a file"
