#!/usr/bin/env bash
# Every documentation link resolves: the relative links of the tracked Markdown files (against the
# file's own folder; URLs and pure anchors skipped), and every `docs/<name>.md` that a tracked source,
# header, script or configuration names (against the repository's root), and every repository path a
# Markdown file quotes in backticks (`recon/camera/rig.cpp`, `tests/daemon/`, or a header by its include
# path, `naneye/recon/camera/rig.hpp`; `{a,b}` lists expanded,
# globs and build outputs skipped), so a moved file cannot leave its docs behind. Exits 1 naming each
# broken one.
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
top='(base|recon|driver|sim|app|daemon|tools|tests|bench|config|scripts|docs|systemd|packaging|cmake)'
while IFS= read -r hit; do
  file=${hit%%:*}
  quoted=${hit#*:}
  quoted=${quoted//\`/}
  case "$quoted" in *'*'* | *'<'* | *'NNN'*) continue ;; esac
  for name in $(eval "echo $quoted"); do
    case "$name" in naneye/*) module=${name#naneye/} && name="${module%%/*}/include/$name" ;; esac
    if [ ! -e "$name" ]; then
      echo "$file: quotes $name, which does not exist"
      bad=1
    fi
  done
done < <(git ls-files -z -- '*.md' | xargs -0 grep -oHE "\`($top|naneye/(base|recon|driver|sim|app|daemon))/[A-Za-z0-9_./{},-]+\`" | sort -u || true)
if [ "$bad" -eq 0 ]; then echo "check-links: every link resolves"; fi
exit "$bad"
