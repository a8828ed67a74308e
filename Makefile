# The two commands: `make run` serves on the bundled defaults; `make test` runs everything.
.PHONY: run test lint bench eval openapi

run:
	cargo run --release -- serve

test: lint
	cargo test --all-targets

lint:
	cargo fmt --check
	cargo clippy --all-targets -- -D warnings

bench:
	cargo bench --bench pipeline

eval:
	cargo run --release -- eval

openapi:
	cargo run --release -- openapi > openapi/openapi.json
