# Quick start: `make demo` renders the built-in city with traffic and writes out/demo.png + out/demo.json;
# `make test` runs the whole suite on lavapipe with validation on. Both install what is missing.

CARGO ?= cargo



.PHONY: deps demo test build release lint fmt clean fuzz

deps:
	./scripts/install-deps

build: deps
	$(CARGO) build --release

demo: deps
	$(CARGO) run --release -- render --scene builtin:city --animate --size 1280x720 --frames 30 --out out/demo.png --stats out/demo.json

test: deps
	CARGO=$(CARGO) ./scripts/check-lean-lib
	$(CARGO) test --all-targets

# Fuzz the graph loader and compiler and the glTF importer, MINUTES each (both at once), with
# the repository's graphs and the shared game levels as seeds; see docs/fuzzing.md.
MINUTES ?= 10
fuzz: deps
	$(CARGO) build --release
	./target/release/cullgraph fuzz graph --seconds $$(( $(MINUTES) * 60 )) --out out/fuzz \
		--seeds graph/examples --seeds tests/graphs/bad --seeds tests/graphs/gpu & \
	./target/release/cullgraph fuzz gltf --seconds $$(( $(MINUTES) * 60 )) --out out/fuzz \
		$$(test -d ../shared/assets && echo --seeds ../shared/assets); \
	gltf=$$?; wait $$!; graph=$$?; test $$gltf = 0 && test $$graph = 0

lint:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --all-targets -- -D warnings
	$(CARGO) clippy --lib --no-default-features -- -D warnings

fmt:
	$(CARGO) fmt --all

clean:
	$(CARGO) clean
	rm -rf out
