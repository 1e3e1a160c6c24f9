#!/usr/bin/env bash
# The web app in a real browser. Builds it and installs Debian's chromium (and Node, if
# missing) and the browser driver (.ci/prepare-web.sh: a no-op when `bash .ci/test` already ran
# it beside `cargo test`), serves web/dist on 127.0.0.1 and runs tests/web/browser_test.mjs:
# the seeded random ride against `seat-twin simulate` (a_w to 1e-9), Kp through the sliders'
# path, unstable and back, a lesson step, a shared link, the file picker and a download,
# screenshots (into target/web-shots/). Each step prints its time.
set -euo pipefail
cd "$(dirname "$0")/../.."

SEED=7
DURATION_S=20
step_start=$(date +%s)
step() {
    local now
    now=$(date +%s)
    echo "== web.sh: previous step took $(( now - step_start )) s; now: $*"
    step_start=$now
}

step "bash .ci/prepare-web.sh (the app's wasm build, chromium, the browser driver)"
bash .ci/prepare-web.sh

step "the CLI's reference: seat-twin simulate, a_w as the app evaluates it"
# The debug build with every feature is the one `cargo test --all-features` just made (with
# the example in the build, features resolve as in the test build: nothing is compiled again).
cargo build --all-features --bin seat-twin --lib --examples
target_dir=$(cargo metadata --format-version 1 --no-deps \
    | python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
work=$(mktemp -d)
server=""
cleanup() {
    if [ -n "$server" ]; then kill "$server" 2>/dev/null || true; fi
    rm -rf "$work"
}
trap cleanup EXIT
for model in twin linear passive; do
    "$target_dir/debug/seat-twin" simulate --model "$model" --scenario random --seed "$SEED" \
        --duration "$DURATION_S" --rate 500 --out "$work/$model.csv" >/dev/null
done
"$target_dir/debug/examples/web_aw" "$work/twin.csv" "$work/linear.csv" "$work/passive.csv" \
    | tee "$work/reference.jsonl"

step "serve web/dist on 127.0.0.1 and run the browser test"
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
python3 -m http.server --bind 127.0.0.1 --directory web/dist "$port" >"$work/server.log" 2>&1 &
server=$!
for _ in $(seq 50); do
    python3 -c 'import sys, urllib.request; urllib.request.urlopen(sys.argv[1], timeout=1)' \
        "http://127.0.0.1:$port/index.html" 2>/dev/null && break
    sleep 0.1
done
node tests/web/browser_test.mjs "http://127.0.0.1:$port/" "$work/reference.jsonl" \
    "$SEED" "$DURATION_S" "$target_dir/web-shots"
step "done"
