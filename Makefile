# The two commands: `make run` serves on the bundled defaults; `make test` runs everything.
.PHONY: setup run test lint bench eval eval-detect openapi deploy-check

# ONNX Runtime's shared library, from the PyPI wheel, into .ort/ (idempotent).
setup:
	scripts/fetch-onnxruntime.sh .ort

run: setup
	cargo run --release -- serve

# --release: one optimised build shared with `make run` and `cargo bench`.
test: setup lint deploy-check
	cargo test --release --all-targets

lint:
	cargo fmt --check
	cargo clippy --all-targets -- -D warnings

bench: setup
	cargo bench

eval:
	cargo run --release -- eval

eval-detect: setup
	cargo run --release -- eval --endpoints detect

# hadolint, kubernetes-validate --strict, kubectl kustomize (offline checks).
deploy-check:
	scripts/check-deploy.sh

openapi:
	cargo run --release -- openapi > openapi/openapi.json
