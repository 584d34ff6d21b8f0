# procfit: `make serve` builds and serves the page, `make test` runs every check CI runs.
# Both install what is missing first (scripts/setup.sh), idempotently.
SHELL := /bin/bash
.SHELLFLAGS := -eu -o pipefail -c
.DEFAULT_GOAL := help

WASM_TARGET := wasm32-unknown-unknown
WASM_DIR := target/wasm
# The threaded build: atomics + shared memory (.cargo/config.toml) need std rebuilt (build-std).
WASM_FLAGS := --release --lib --target $(WASM_TARGET) --target-dir $(WASM_DIR) \
	-Z build-std=panic_abort,std

.PHONY: help setup setup-test wasm serve test lint test-rust test-e2e bench clean-pkg

help:
	@echo "make serve   build the wasm and serve the page on http://127.0.0.1:8080/ (PORT=... to change)"
	@echo "make test    lint, Rust tests, wasm build and browser tests (what CI runs)"
	@echo "make bench   print the benchmark tables"

setup:
	@scripts/setup.sh

setup-test:
	@scripts/setup.sh --test

wasm: setup
	cargo +nightly build $(WASM_FLAGS) --features threads
	wasm-bindgen --target web --out-dir pkg $(WASM_DIR)/$(WASM_TARGET)/release/procfit.wasm

serve: wasm
	python3 scripts/serve.py

lint: setup
	cargo fmt --all --check
	cargo clippy --workspace --all-targets --locked -- -D warnings
	cargo +nightly clippy $(WASM_FLAGS) --features threads -- -D warnings
	RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --locked --quiet

test-rust:
	cargo test --workspace --locked

test-e2e: wasm
	node --test --test-concurrency=1 tests/e2e/

test: setup-test lint test-rust test-e2e

bench: wasm
	cargo bench --workspace --locked
	node scripts/bench-wasm.mjs
