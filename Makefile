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

.PHONY: help setup setup-test wasm wasm-st dist serve test lint test-rust test-e2e test-fuzz bench bench-page clean-pkg

help:
	@echo "make serve   build the wasm and serve the page on http://127.0.0.1:8080/ (PORT=... to change)"
	@echo "make test    lint, Rust tests, wasm build and browser tests (what CI runs)"
	@echo "make bench   print the benchmark tables (make bench-page: the page's, in Chromium)"
	@echo "make dist    build dist/, a folder any static host serves as is"

setup:
	@scripts/setup.sh

setup-test:
	@scripts/setup.sh --test

wasm: setup
	cargo +nightly build $(WASM_FLAGS) --features threads
	wasm-bindgen --target web --out-dir pkg $(WASM_DIR)/$(WASM_TARGET)/release/procfit.wasm

# The single-threaded fallback for pages served without COOP/COEP (no SharedArrayBuffer): the
# config's atomics rustflags are overridden, so std needs no rebuild.
wasm-st: setup
	RUSTFLAGS="" cargo +nightly build --release --lib --target $(WASM_TARGET) --target-dir target/wasm-st
	wasm-bindgen --target web --out-dir pkg-st target/wasm-st/$(WASM_TARGET)/release/procfit.wasm

# A static site: the page, both wasm builds and the few three.js modules the page imports.
# Served with COOP/COEP it runs threaded; without, single-threaded (and says so).
THREE_FILES := build/three.module.js build/three.core.js LICENSE \
	examples/jsm/loaders/GLTFLoader.js examples/jsm/controls/OrbitControls.js \
	examples/jsm/utils/BufferGeometryUtils.js examples/jsm/utils/SkeletonUtils.js
dist: wasm wasm-st
	rm -rf dist && mkdir -p dist
	cp -r index.html www pkg pkg-st dist/
	cd node_modules/three && for f in $(THREE_FILES); do install -D -m 644 $$f ../../dist/node_modules/three/$$f; done
	@echo "dist/ is ready: serve it from any static host (COOP/COEP headers enable threads)"

serve: wasm
	python3 scripts/serve.py

lint: setup
	cargo fmt --all --check
	cargo clippy --workspace --all-targets --locked -- -D warnings
	cargo +nightly clippy $(WASM_FLAGS) --features threads -- -D warnings
	RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --locked --quiet
	# The page's JavaScript against its JSDoc types (page and worker have different globals).
	npx --no-install tsc -p tsconfig.json --noEmit --checkJs
	npx --no-install tsc -p tsconfig.worker.json --noEmit --checkJs

test-rust:
	cargo test --workspace --locked

test-e2e: dist
	node --test --test-concurrency=1 tests/e2e/

# A short libFuzzer run of every target in fuzz/ from its committed corpus (new inputs go to a
# scratch folder, never into the repository); the long runs are in fuzz/README.md.
FUZZ_TARGETS := decode_photo mask_image params_json tree_colors import_glb
FUZZ_RUNS ?= 20000
test-fuzz: setup-test
	PROCFIT_WRITE_FUZZ_SEEDS=1 cargo test --locked --test fuzz_corpus --quiet
	cd fuzz && cargo +nightly fuzz build -s none
	for t in $(FUZZ_TARGETS); do \
	  rm -rf target/fuzz-scratch/$$t && mkdir -p target/fuzz-scratch/$$t && \
	  (cd fuzz && cargo +nightly fuzz run -s none $$t ../target/fuzz-scratch/$$t corpus/$$t -- \
	    -runs=$(FUZZ_RUNS) -rss_limit_mb=2048 -timeout=10 \
	    -artifact_prefix=../target/fuzz-scratch/crash-$$t- 2>&1 | tail -n 3) || exit 1; \
	done

test: setup-test lint test-rust test-e2e test-fuzz

bench: wasm
	cargo bench --workspace --locked
	node scripts/bench-wasm.mjs

bench-page: wasm
	node tests/e2e/bench.mjs
