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

RAYON_HELPER = pkg/snippets/wasm-bindgen-rayon-*/src/workerHelpers.no-bundler.js

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
	@# wasm-bindgen-rayon 1.3's no-bundler helper starts each thread with init's positional
	@# parameters, which wasm-bindgen warns about on the console once per thread: pass the
	@# options object instead (and fail loudly if a new version changes the line).
	sed -i 's/await pkg.default(data.module, data.memory);/await pkg.default({ module_or_path: data.module, memory: data.memory });/' $(RAYON_HELPER)
	grep -q 'module_or_path: data.module' $(RAYON_HELPER)

# The single-threaded fallback for pages served without COOP/COEP (no SharedArrayBuffer): the
# config's atomics rustflags are overridden, so std needs no rebuild.
wasm-st: setup
	RUSTFLAGS="" cargo +nightly build --release --lib --target $(WASM_TARGET) --target-dir target/wasm-st
	wasm-bindgen --target web --out-dir pkg-st target/wasm-st/$(WASM_TARGET)/release/procfit.wasm

# A static site: the page, both wasm builds and the few three.js modules the page imports
# (minified three.js, as the import map names it). Served with COOP/COEP it runs threaded;
# without, single-threaded (and says so). The wasm is optimised by wasm-opt (npm `binaryen`),
# which also drops the function-name section (dev builds keep it for readable stack traces), and
# every text/wasm file gets .br and .gz copies for hosts (and scripts/serve.py) that send them.
THREE_FILES := build/three.module.min.js build/three.core.min.js LICENSE \
	examples/jsm/loaders/GLTFLoader.js examples/jsm/controls/OrbitControls.js \
	examples/jsm/utils/BufferGeometryUtils.js examples/jsm/utils/SkeletonUtils.js
# The features rustc's wasm32 target and .cargo/config.toml enable, so wasm-opt adds no others.
WASM_OPT := node_modules/.bin/wasm-opt -O2 --strip-debug --strip-producers \
	--enable-bulk-memory --enable-mutable-globals --enable-sign-ext --enable-nontrapping-float-to-int \
	--enable-reference-types --enable-multivalue
dist: wasm wasm-st
	rm -rf dist && mkdir -p dist
	cp -r index.html www pkg pkg-st dist/
	$(WASM_OPT) --enable-threads pkg/procfit_bg.wasm -o dist/pkg/procfit_bg.wasm
	$(WASM_OPT) pkg-st/procfit_bg.wasm -o dist/pkg-st/procfit_bg.wasm
	cd node_modules/three && for f in $(THREE_FILES); do install -D -m 644 $$f ../../dist/node_modules/three/$$f; done
	node scripts/precompress.mjs dist | tail -1
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
