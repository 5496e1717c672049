# bicycle-xval: developer targets. The virtualenv lives in .venv; the stamp file
# .venv/.installed is refreshed whenever pyproject.toml changes.

PYTHON ?= python3
VENV = .venv
# single-threaded BLAS: the matrices here are small (<= 500), threads only contend with the
# worker processes of `bicycle-xval run` (a 500x250 SVD took 4 s threaded, 28 ms not)
export OPENBLAS_NUM_THREADS ?= 1
export OMP_NUM_THREADS ?= 1
STAMP = $(VENV)/.installed

.PHONY: venv test report example bench clean

venv: $(STAMP)

$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml $(VENV)/bin/python
	$(VENV)/bin/python -m pip install -e '.[test]'
	touch $(STAMP)

test: $(STAMP)
	$(VENV)/bin/python -m pytest -n auto --dist loadgroup --durations=5

report: $(STAMP)
	$(VENV)/bin/bicycle-xval run --out reports/latest

example: $(STAMP)  ## the committed example report: markdown, figures, summary.json (no CSVs, no HTML)
	$(VENV)/bin/bicycle-xval run --out reports/example --no-data --no-html

bench: $(STAMP)
	$(VENV)/bin/python benchmarks/run.py

clean:  ## build leftovers and the generated-code cache (regenerated on next use)
	rm -rf .cache build dist *.egg-info
	rm -rf "$${BICYCLE_XVAL_CACHE:-$${XDG_CACHE_HOME:-$$HOME/.cache}/bicycle-xval}"
