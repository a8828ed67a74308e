# The two commands: `make run` serves on the bundled defaults; `make test` runs everything.
.PHONY: setup run test lint bench eval eval-detect stress lobo train-field quantize-field calibration scene-check openapi deploy-check browser-test

# ONNX Runtime's shared library, from the PyPI wheel, into .ort/ (idempotent).
setup:
	scripts/fetch-onnxruntime.sh .ort

run: setup
	cargo run --release -- serve

# --release: one optimised build shared with `make run` and `cargo bench`.
test: setup lint deploy-check
	cargo test --release --all-targets
	scripts/browser-test.sh

# The page at GET / in headless Chromium (installs chromium and selenium if missing).
browser-test:
	scripts/browser-test.sh

lint:
	cargo fmt --check
	cargo clippy --all-targets -- -D warnings

bench: setup
	cargo bench

eval: setup
	cargo run --release -- eval

eval-detect: setup
	cargo run --release -- eval --endpoints detect

# Synthetic scenes the development split lacks (docs/ACCURACY.md), drawn into out/stress
# and evaluated from a photo alone and from the true ends.
stress: setup
	training/.venv/bin/python scripts/stress.py out/stress
	cargo run --release -- eval --dataset out/stress --endpoints detect
	cargo run --release -- eval --dataset out/stress --endpoints gt

# Leave-one-background-out: train one network per held-out group (out/field-GROUP-fp32.onnx,
# about 15-20 minutes each on 2 cores), quantize it as the bundled one
# (out/field-GROUP.onnx), then score each on its held-out photos.
lobo: setup calibration
	for g in white wood blue hard; do \
	  training/.venv/bin/python training/train_field.py --backbone lite0 --rich-textures --line-textures 0.15 --steps 2000 --holdout $$g --out out/field-$$g-fp32.onnx; \
	  training/.venv/bin/python training/quantize_field.py out/field-$$g-fp32.onnx out/field-$$g.onnx --calibration out/calibration; \
	done
	cargo build --release
	python3 scripts/lobo.py --binary $${CARGO_TARGET_DIR:-target}/release/ariadne --endpoints detect
	python3 scripts/lobo.py --binary $${CARGO_TARGET_DIR:-target}/release/ariadne --endpoints gt

# The bundled model (about 15-20 minutes on 2 cores), trained in float, then quantized;
# see models/README.md.
train-field:
	training/.venv/bin/python training/train_field.py --backbone lite0 --rich-textures --line-textures 0.15 --steps 2000 --out models/cable_field_fp32.onnx
	$(MAKE) quantize-field

# The service's network: the float one with 8-bit weights and activations (a minute).
quantize-field: calibration
	training/.venv/bin/python training/quantize_field.py models/cable_field_fp32.onnx models/cable_field.onnx --calibration out/calibration

# Drawn scenes that set the quantized networks' activation ranges (a seed no
# evaluation uses).
calibration:
	rm -rf out/calibration
	training/.venv/bin/python scripts/stress.py out/calibration --seed 40 --per-kind 4

# The training scenes are still those the bundled model saw (models/README.md).
scene-check:
	test "$$(training/.venv/bin/python training/train_field.py --line-textures 0.15 --scene-hash 4 | tail -1)" = "scenes b026b36c43e56f06f5928470d2978caf"

# hadolint, kubernetes-validate --strict, kubectl kustomize (offline checks).
deploy-check:
	scripts/check-deploy.sh

openapi:
	cargo run --release -- openapi > openapi/openapi.json
