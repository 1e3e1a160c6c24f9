#!/usr/bin/env bash
# What the web check (.ci/checks/web.sh) needs before it can drive the app in a browser, none
# of it from the native build: the web app itself (web/build.sh: the wasm32 target,
# wasm-bindgen-cli at the locked version, the wasm32 release build in its own target
# directory), Debian's chromium (and Node with npm, if missing) and the browser driver
# (playwright-core, pinned in tests/web/package.json). Idempotent: a second run installs and
# compiles nothing. `bash .ci/test` starts it beside `cargo test`, so that downloads, installs
# and the wasm32 build fill the cores the native test build leaves idle; web.sh runs it again
# (then a no-op) so that it also works alone.
set -euo pipefail
cd "$(dirname "$0")/.."

step_start=$(date +%s)
step() {
    local now
    now=$(date +%s)
    echo "== prepare-web.sh: previous step took $(( now - step_start )) s; now: $*"
    step_start=$now
}

step "bash web/build.sh"
bash web/build.sh

# Debian's chromium, and Node with npm for the browser driver, if missing (apt-get, once).
missing=""
command -v chromium >/dev/null || missing="$missing chromium"
command -v npm >/dev/null || missing="$missing nodejs npm"
if [ -n "$missing" ]; then
    step "apt-get install$missing"
    if [ "$(id -u)" -eq 0 ]; then sudo=""; else sudo="sudo"; fi
    $sudo apt-get update -qq
    # shellcheck disable=SC2086
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $missing
fi

if [ ! -d tests/web/node_modules/playwright-core ]; then
    step "npm ci (playwright-core, the browser driver)"
    npm ci --prefix tests/web --no-audit --no-fund
fi
step "done"
