# The whole set-up on a fresh machine: `make run` and `make test` both bootstrap .venv.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
PIP := $(BIN)/pip install --constraint constraints.txt
STAMP := $(VENV)/.installed
# Test processes side by side (pytest-xdist): most tests wait on worlds, agents and sockets rather
# than compute, so two share two cores well. TEST_WORKERS=0 runs them in this one process.
TEST_WORKERS ?= 2
LIBUSB := /usr/lib/x86_64-linux-gnu/libusb-1.0.so.0 /usr/lib/aarch64-linux-gnu/libusb-1.0.so.0

.PHONY: run test test-quick system-deps browser-deps clean

run: $(STAMP)
	$(BIN)/homebot run --seed 0

test: $(STAMP)
	$(BIN)/python -m pytest -n $(TEST_WORKERS)

test-quick: $(STAMP)
	$(BIN)/python -m pytest -n $(TEST_WORKERS) -m "not slow"

$(STAMP): pyproject.toml constraints.txt | system-deps browser-deps
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(PIP) --quiet -e '.[test]'
	touch $(STAMP)

# open3d needs libusb-1.0 at import time; install it when root, else say exactly what to run.
system-deps:
	@if ! ls $(LIBUSB) >/dev/null 2>&1 && ! ldconfig -p 2>/dev/null | grep -q libusb-1.0.so.0; then \
		if [ "$$(id -u)" = "0" ]; then \
			echo "installing libusb-1.0-0 (open3d needs it)"; \
			apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libusb-1.0-0; \
		else \
			echo "open3d needs the system library libusb-1.0; run: sudo apt-get install -y libusb-1.0-0" >&2; \
			exit 1; \
		fi; \
	fi

# The inspector's browser tests drive Debian's chromium through chromium-driver; install them when
# root, else say exactly what to run (the tests skip without them).
browser-deps:
	@if ! command -v chromium >/dev/null 2>&1 || ! command -v chromedriver >/dev/null 2>&1; then \
		if [ "$$(id -u)" = "0" ]; then \
			echo "installing chromium and chromium-driver (the inspector's browser tests use them)"; \
			apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium chromium-driver; \
		else \
			echo "the inspector's browser tests need chromium; run: sudo apt-get install -y chromium chromium-driver" >&2; \
		fi; \
	fi

clean:
	rm -rf $(VENV) runs build *.egg-info
