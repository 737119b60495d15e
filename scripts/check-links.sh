#!/usr/bin/env bash
# Every documentation link resolves: the relative links of the tracked Markdown files (against the
# file's own folder; URLs and pure anchors skipped), and every `docs/<name>.md` that a tracked source,
# header, script or configuration names (against the repository's root). Exits 1 naming each broken one.
set -euo pipefail
cd "$(dirname "$0")/.."
bad=0
while IFS= read -r md; do
  dir=$(dirname "$md")
  while IFS= read -r target; do
    path=${target%%#*}
    [ -z "$path" ] && continue
    case "$path" in http://* | https://* | mailto:*) continue ;; esac
    if [ ! -e "$dir/$path" ]; then
      echo "$md: broken link ($target)"
      bad=1
    fi
  done < <(grep -oE '\]\([^) ]+\)' "$md" | sed -E 's/^\]\(//; s/\)$//' || true)
done < <(git ls-files '*.md')
while IFS= read -r hit; do
  file=${hit%%:*}
  name=${hit#*:}
  if [ ! -e "$name" ]; then
    echo "$file: names $name, which does not exist"
    bad=1
  fi
done < <(git ls-files -z -- '*.cpp' '*.hpp' '*.toml' '*.in' '*.sh' '*.txt' '*.cmake' '*.js' '*.mjs' '*.html' '*.yaml' |
  xargs -0 grep -oHE 'docs/[A-Za-z0-9_./-]+\.md' | sort -u || true)
if [ "$bad" -eq 0 ]; then echo "check-links: every link resolves"; fi
exit "$bad"
