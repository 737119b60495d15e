#!/usr/bin/env bash
# The module graph of docs/architecture.md is the one CMake links: every edge of BUILD/module_graph.txt
# (written at configure time from the targets' link libraries) must be in the doc's block between
# "<!-- module-graph -->" and "<!-- /module-graph -->", and every edge there must exist.
#   scripts/check-module-graph.sh BUILD_DIR
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:?usage: check-module-graph.sh BUILD_DIR}
built=$(sort -u "$build/module_graph.txt")
doc=$(sed -n '/<!-- module-graph -->/,/<!-- \/module-graph -->/p' docs/architecture.md | grep -E '^[a-z_]+ -> [a-z_]+$' | sort -u || true)
[ -n "$doc" ] || { echo "docs/architecture.md has no module-graph block"; exit 1; }
missing=$(comm -23 <(echo "$built") <(echo "$doc"))
stale=$(comm -13 <(echo "$built") <(echo "$doc"))
[ -z "$missing" ] || printf 'linked in CMake but not in docs/architecture.md:\n%s\n' "$missing"
[ -z "$stale" ] || printf 'in docs/architecture.md but not linked in CMake:\n%s\n' "$stale"
[ -z "$missing$stale" ] && echo "check-module-graph: docs/architecture.md shows the $(echo "$built" | wc -l) edges CMake links"
[ -z "$missing$stale" ]
