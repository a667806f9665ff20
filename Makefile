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

# the real-window tests (tests/gui/test_real_window.py) need an X server (Xvfb) and Qt's xcb libraries, installed
# here when missing and apt-get can run (as root; stdin closed, a timeout: a stuck apt never hangs the build)
XCB_PKGS := xvfb libxcb-cursor0 libxcb-icccm4 libxcb-keysyms1 libxcb-image0 libxcb-render-util0 libxcb-shape0 \
	libxcb-randr0 libxcb-xinerama0 libxcb-xkb1 libxkbcommon-x11-0
# a fresh machine's package lists may be empty: on a failed install, update them once and try again
XVFB := { command -v Xvfb && ldconfig -p | grep -q libxcb-cursor.so.0 && ldconfig -p | grep -q libxcb-icccm.so.4; } >/dev/null \
	|| { [ "$$(id -u)" = 0 ] && { timeout 300 apt-get install -y -q $(XCB_PKGS) >/dev/null 2>&1 </dev/null \
	|| { timeout 300 apt-get update -q >/dev/null 2>&1 </dev/null && timeout 300 apt-get install -y -q $(XCB_PKGS) \
	>/dev/null </dev/null; }; }; } || echo "make: Xvfb or Qt's xcb libraries missing and not installable (see README, Install)"

# the CI set on two pytest-xdist workers (CI has 2 cores), a whole test file to a worker: a module-scoped fixture
# (a rendered session) is built once, largest files first; `make test XDIST=` runs it in one process
XDIST ?= -n 2 --dist loadfile
test: $(STAMP)
	@$(XVFB)
	$(PY) -m pytest -m "not slow" $(XDIST)

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
