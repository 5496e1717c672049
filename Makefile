# bicycle-xval: developer targets. The virtualenv lives in .venv; the stamp file
# .venv/.installed is refreshed whenever pyproject.toml changes.

PYTHON ?= python3
VENV = .venv
# single-threaded BLAS: the matrices here are small (<= 500), threads only contend with the
# worker processes of `bicycle-xval run` (a 500x250 SVD took 4 s threaded, 28 ms not)
export OPENBLAS_NUM_THREADS ?= 1
export OMP_NUM_THREADS ?= 1
STAMP = $(VENV)/.installed

.PHONY: venv test test-slow test-bicycles report example bench clean mutants mutants-table mutants-readme

venv: $(STAMP)

$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml $(VENV)/bin/python
	$(VENV)/bin/python -m pip install -e '.[all,test]'
	touch $(STAMP)

test: $(STAMP)
	$(VENV)/bin/python -m pytest -n auto --durations=5 -m "not bicycles and not slow" \
	  --conformance-depth quick

# The tests marked `slow`: the harness's own processes (signals to the process tree, workers
# that die or hang, sweeps on a Dask cluster, cold compiler builds, the wheel) and whole runs;
# then the conformance suite at its full depth on every registered engine (make test runs it
# at --conformance-depth quick). Kept out of `make test`'s 90 s; .ci/run runs them.
test-slow: $(STAMP)
	$(VENV)/bin/python -m pytest -n auto --durations=5 -m "slow and not bicycles"
	$(VENV)/bin/python -m pytest -n auto --durations=5 comparisons/conformance/test_conformance.py

# The ten measured bicycles BicycleParameters ships, end to end (import, run --quick --model on
# every default engine, diagnose): the heaviest study (~450 stages, minutes), kept out of
# `make test`'s 90 s; .ci/run runs both.
test-bicycles: $(STAMP)
	$(VENV)/bin/python -m pytest -n auto -m bicycles tests/test_real_bicycles.py

report: $(STAMP)
	$(VENV)/bin/bicycle-xval run --out reports/latest

example: $(STAMP)  ## the committed example report: markdown, figures, summary.json (no CSVs, no HTML)
	$(VENV)/bin/bicycle-xval run --out reports/example --no-data --no-html

bench: $(STAMP)
	$(VENV)/bin/python benchmarks/run.py

# Mutation testing (not part of `make test`): mutmut, module by module (tests/mutation.py): each
# module of pyproject.toml's [tool.mutmut] set is mutated alone in a scratch copy under
# build/mutation/, against its own fast test selection ([tool.bicycle-xval.mutation.tests]),
# and its result committed in tests/mutation_results/. `make mutants` measures every module
# whose result is missing or stale (module or tests changed), so an interrupted run resumes;
# the whole set is hours on the 2-core machine (README, "Tests"). MODULE narrows it, e.g.
# make mutants MODULE=comparisons/judgments/rows.py. `make mutants-table` prints the scores
# (a module with no result yet shows an earlier round's reading, tests/mutation_readings.toml).
MUTATION_STAMP = $(VENV)/.installed-mutation
MODULE ?=

$(MUTATION_STAMP): pyproject.toml $(VENV)/bin/python
	$(VENV)/bin/python -m pip install -e '.[all,test,mutation]'
	touch $(MUTATION_STAMP)

mutants: $(MUTATION_STAMP)
	$(VENV)/bin/python tests/mutation.py $(if $(MODULE),$(MODULE),--all) --children 2

mutants-table: $(STAMP)
	$(VENV)/bin/python tests/mutation.py --table

# the table and the list of equivalent mutants into README.md's two generated blocks
# (tests/test_mutation_tool.py fails while they differ from the committed results)
mutants-readme: $(STAMP)
	$(VENV)/bin/python tests/mutation.py --readme

clean:  ## build leftovers and the generated-code cache (regenerated on next use)
	rm -rf .cache build dist *.egg-info mutants mutants.log
	rm -rf "$${BICYCLE_XVAL_CACHE:-$${XDG_CACHE_HOME:-$$HOME/.cache}/bicycle-xval}"
