# Quick start: `make demo` renders the built-in city and writes out/demo.png + out/demo.json;
# `make test` runs the whole suite on lavapipe with validation on. Both install what is missing.

CARGO ?= cargo



.PHONY: deps demo test build release lint fmt clean

deps:
	./scripts/install-deps

build: deps
	$(CARGO) build --release

demo: deps
	$(CARGO) run --release -- render --scene builtin:city --size 1280x720 --frames 3 --out out/demo.png --stats out/demo.json

test: deps
	CARGO=$(CARGO) ./scripts/check-lean-lib
	$(CARGO) test --all-targets

lint:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --all-targets -- -D warnings
	$(CARGO) clippy --lib --no-default-features -- -D warnings

fmt:
	$(CARGO) fmt --all

clean:
	$(CARGO) clean
	rm -rf out
