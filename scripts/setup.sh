#!/usr/bin/env bash
# Installs what procfit's build and tests need, idempotently: each step checks first and is a
# no-op when its tool is already there, so a warm run takes a few seconds.
#
#   scripts/setup.sh          build tools: nightly rust-src + wasm32 target, wasm-bindgen-cli
#                             matching Cargo.lock, npm packages from package-lock.json
#   scripts/setup.sh --test   the above, plus Debian's chromium for the browser tests and
#                             cargo-fuzz for the short fuzz runs
set -euo pipefail
cd "$(dirname "$0")/.."

want_browser=0
[ "${1:-}" = "--test" ] && want_browser=1

say() { printf 'setup: %s\n' "$*" >&2; }
die() { printf 'setup: %s\n' "$*" >&2; exit 1; }

command -v cargo >/dev/null || die "cargo not found: install Rust with rustup (https://rustup.rs)"
command -v rustup >/dev/null || die "rustup not found: procfit needs rustup to manage the nightly toolchain"
command -v node >/dev/null || die "node not found: install Node.js 20+ (Debian: apt-get install nodejs npm)"
command -v npm >/dev/null || die "npm not found: install npm (Debian: apt-get install npm)"
command -v python3 >/dev/null || die "python3 not found: install Python 3 (Debian: apt-get install python3)"

# 1. Nightly with rust-src and the wasm32 target (threaded wasm needs build-std).
if ! rustup toolchain list | grep -q '^nightly'; then
  say "installing the nightly toolchain"
  rustup toolchain install nightly --profile minimal
fi
if ! rustup component list --toolchain nightly --installed 2>/dev/null | grep -q '^rust-src'; then
  say "adding rust-src to nightly"
  rustup component add rust-src --toolchain nightly
fi
if ! rustup target list --toolchain nightly --installed 2>/dev/null | grep -q '^wasm32-unknown-unknown$'; then
  say "adding the wasm32-unknown-unknown target to nightly"
  rustup target add wasm32-unknown-unknown --toolchain nightly
fi

# 2. wasm-bindgen-cli at exactly the version of the wasm-bindgen crate in Cargo.lock.
wb_version=$(awk '/^name = "wasm-bindgen"$/{getline; gsub(/version = |"/, ""); print; exit}' Cargo.lock)
[ -n "$wb_version" ] || die "wasm-bindgen not found in Cargo.lock"
have=$(wasm-bindgen --version 2>/dev/null | awk '{print $2}' || true)
if [ "$have" != "$wb_version" ]; then
  say "installing wasm-bindgen-cli $wb_version (found: ${have:-none}); takes a few minutes once"
  # Not --locked: one of the CLI's locked dependency versions is missing from the index.
  cargo install wasm-bindgen-cli --version "$wb_version" --quiet
fi

# 3. npm packages, exactly as locked; again only when the lock file changes.
lock_sum=$(sha256sum package-lock.json | cut -d' ' -f1)
if [ "$(cat node_modules/.procfit-lock 2>/dev/null || true)" != "$lock_sum" ]; then
  say "installing npm packages (npm ci)"
  npm ci --no-audit --no-fund --loglevel=error
  echo "$lock_sum" > node_modules/.procfit-lock
fi

# 4. Chromium for the browser tests (Debian's package; playwright cannot download browsers here).
if [ "$want_browser" = 1 ] && [ ! -x /usr/bin/chromium ]; then
  if [ "$(id -u)" != 0 ]; then
    die "chromium missing: run 'sudo apt-get install chromium' (Debian's package), then retry"
  fi
  say "installing Debian's chromium"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends chromium >/dev/null
fi
# 5. cargo-fuzz for the short fuzz runs of `make test` (libFuzzer, on the nightly toolchain).
if [ "$want_browser" = 1 ] && ! cargo fuzz --version >/dev/null 2>&1; then
  say "installing cargo-fuzz; takes a few minutes once"
  cargo install cargo-fuzz --version 0.13.2 --locked --quiet
fi
exit 0
