#!/usr/bin/env bash
# Builds the web app into web/dist/ (index.html, seat_twin.js, seat_twin_bg.wasm): a static
# folder any web server or course page can host. Installs what it needs first: the rustup
# target wasm32-unknown-unknown and wasm-bindgen-cli at the exact version of the locked
# wasm-bindgen (from crates.io). Serve it with: python3 -m http.server -d web/dist 8080
set -euo pipefail
cd "$(dirname "$0")/.."

step() { echo "== web/build.sh: $*"; }
t0=$(date +%s)

step "rustup target add wasm32-unknown-unknown"
rustup target add wasm32-unknown-unknown

# The CLI must match the library's version exactly (its JS glue and the .wasm's schema).
version=$(python3 - <<'PY'
import re
lock = open("Cargo.lock").read()
m = re.search(r'\[\[package\]\]\nname = "wasm-bindgen"\nversion = "([^"]+)"', lock)
print(m.group(1) if m else "")
PY
)
if [ -z "$version" ]; then
    echo "web/build.sh: no wasm-bindgen in Cargo.lock" >&2
    exit 1
fi
if [ "$(wasm-bindgen --version 2>/dev/null | awk '{print $2}')" != "$version" ]; then
    # Unoptimised (opt-level 0): measured here, it compiles in 84 s instead of 190 s (2.2 CPU-min
    # instead of 5.7) and turns this crate's wasm into the same bytes in 6 s instead of 2.
    step "cargo install wasm-bindgen-cli --version $version (opt-level 0)"
    CARGO_PROFILE_RELEASE_OPT_LEVEL=0 cargo install wasm-bindgen-cli --version "$version"
fi

# A target directory of its own (target/web): the wasm32 build then never waits on the lock
# of a native build in target/, so `bash .ci/test` can run the two side by side.
target_dir=$(cargo metadata --format-version 1 --no-deps \
    | python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
web_target="$target_dir/web"
step "cargo build --release --lib --target wasm32-unknown-unknown --target-dir $web_target"
cargo build --release --lib --target wasm32-unknown-unknown --target-dir "$web_target"
wasm="$web_target/wasm32-unknown-unknown/release/seat_twin.wasm"

# Staged in a hidden folder, moved into place at the end: a failed build leaves the last
# good web/dist/ as it was.
stage=web/.dist.tmp
rm -rf "$stage"
mkdir -p "$stage"
step "wasm-bindgen --target web"
wasm-bindgen --target web --no-typescript --out-dir "$stage" --out-name seat_twin "$wasm"
cp web/index.html "$stage/"
rm -rf web/dist
mv "$stage" web/dist

size=$(stat -c %s web/dist/seat_twin_bg.wasm)
gz=$(gzip -9 -c web/dist/seat_twin_bg.wasm | wc -c)
step "web/dist/ written in $(( $(date +%s) - t0 )) s: seat_twin_bg.wasm $(( size / 1024 )) KiB, $(( gz / 1024 )) KiB gzipped"
