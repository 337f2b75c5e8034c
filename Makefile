# The two commands of the quick start: `make run` and `make test`. Both create .venv when missing.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
# The OCR models: the rapidocr wheel carries the PP-OCRv6 detection and recognition ONNX files, which
# gauged runs with its own onnxruntime code (gauged/reader/ocr/engine.py). --no-deps: none of the
# package's Python dependencies (downloaders, config libraries) is used.
OCR_PACKAGE := rapidocr==3.10.0
# Re-install whenever pyproject.toml or constraints.txt changes. constraints.txt pins every package to the
# versions the suite passes with (a newer OpenCV or onnxruntime changes JPEG bytes and OCR readings).
CONSTRAINTS := constraints.txt
RUN_STAMP  := $(VENV)/.installed-run
TEST_STAMP := $(VENV)/.installed-test

.PHONY: run test bench clean help

help:
	@echo "make run    - install into .venv and run gauged on the embedded default (replays the demo)"
	@echo "make test   - install gauged[test] into .venv and run the whole test suite"
	@echo "make bench  - run the benchmarks in bench/"
	@echo "make clean  - remove .venv and outputs"

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(RUN_STAMP): pyproject.toml $(CONSTRAINTS) | $(BIN)/python
	$(BIN)/python -m pip install --quiet -c $(CONSTRAINTS) -e .
	$(BIN)/python -m pip install --quiet --no-deps $(OCR_PACKAGE)
	@touch $@

# The suite includes a training smoke test, so the test install has the train extra (CPU torch).
$(TEST_STAMP): pyproject.toml $(CONSTRAINTS) | $(BIN)/python
	$(BIN)/python -m pip install --quiet -c $(CONSTRAINTS) -e ".[test,train]"
	$(BIN)/python -m pip install --quiet --no-deps $(OCR_PACKAGE)
	@touch $@ $(RUN_STAMP)

run: $(RUN_STAMP)
	$(BIN)/gauged run

# System tools the deployment tests use (systemd-analyze, promtool, prometheus); as root on CI it
# installs them with apt, elsewhere it prints the command and the tests that need them skip.
test: $(TEST_STAMP)
	bash deploy/ci/install-system-deps.sh
	$(BIN)/python -m pytest

bench: $(TEST_STAMP)
	@for script in bench/bench_*.py; do echo "== $$script"; $(BIN)/python $$script || exit 1; done

clean:
	rm -rf $(VENV) gauged-out gauged-state .pytest_cache build *.egg-info
