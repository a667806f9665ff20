# Two commands do all set-up on a fresh machine: `make demo` and `make test`.
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-stamp
export QT_QPA_PLATFORM ?= offscreen

.PHONY: demo demo-quick test test-all bench screenshots package clean

$(STAMP): pyproject.toml
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test]'
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/lps demo --out demo-output

demo-quick: $(STAMP)
	$(VENV)/bin/lps demo --quick --out demo-output-quick

# the real-window tests (tests/gui/test_real_window.py) need an X server: Xvfb, installed here when missing and
# apt-get can run without asking (root, no lock held); timeout: a stuck apt never hangs the build
XVFB := command -v Xvfb >/dev/null || { [ "$$(id -u)" = 0 ] && timeout 300 apt-get install -y -q xvfb \
	libxcb-cursor0 libxcb-icccm4 libxcb-keysyms1 >/dev/null </dev/null; } || echo "make: Xvfb missing and not installable: the real-window tests will say so"

test: $(STAMP)
	@$(XVFB)
	$(PY) -m pytest -m "not slow"

test-all: $(STAMP)
	@$(XVFB)
	$(PY) -m pytest

bench: $(STAMP)
	for b in benchmarks/bench_*.py; do $(PY) $$b || exit 1; done

screenshots: $(STAMP)
	$(PY) -m lps_gui.gui.screenshots docs/screenshots
	@$(XVFB)
	LPS_SCREENSHOTS=docs/screenshots/1000x700 $(PY) -m pytest -q tests/gui/test_real_window.py -k 1000x700

package: $(STAMP)
	$(PY) -m pip install -q -e '.[package]'
	$(VENV)/bin/pyinstaller --noconfirm --distpath dist --workpath build packaging/lps-gui.spec

clean:
	rm -rf build dist demo-output demo-output-quick .pytest_cache
