# prg — run `make help` for the targets.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
EXTRAS ?= dev,docs,sweep,speech,speech-base,speech-moonshine,browser,lasa
# Debian packages: espeak-ng speaks the test and demo words, sox converts their audio, chromium
# runs the study pages in the browser tests (Playwright drives it; no `playwright install`)
SYSTEM_PACKAGES ?= espeak-ng sox chromium
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
STAMP := $(VENV)/.setup-$(shell cat pyproject.toml constraints.txt | sha1sum | cut -c1-12)
export PATH := $(CURDIR)/$(BIN):$(PATH)

.DEFAULT_GOAL := help
.PHONY: help system setup constraints demo baselines paper converged test test-all lint format bench results clean mutate docs

help: ## Show this help
	@awk 'BEGIN {FS = ":.*## "} /^[a-zA-Z_-]+:.*## / {printf "  \033[36m%-10s\033[0m %s\n", $$1, $$2}' $(MAKEFILE_LIST)

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

# constraints.txt pins every other package to the versions the results were made with, so a
# fresh machine installs the same numerics (`make constraints` writes it from the .venv).
$(STAMP): pyproject.toml constraints.txt | $(BIN)/python
	@# torch first: the pinned CPU wheel; a looser requirement would pull a multi-GB CUDA build
	$(BIN)/pip install -q torch==2.13.0
	$(BIN)/pip install -q -c constraints.txt -e ".[$(EXTRAS)]"
	@rm -f $(VENV)/.setup-*
	@touch $@

system: ## Install the Debian packages the tests and the demo use, if missing (root or sudo)
	@missing=""; for p in $(SYSTEM_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
		echo "installing Debian packages:$$missing"; \
		$(SUDO) apt-get update -qq && \
		DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; \
	fi

setup: system $(STAMP) ## Create .venv, install system packages, torch (CPU) and the project (idempotent)

# Torch splits some sums (the image networks' convolutions) by thread, so results are the same bytes
# only for the same number of threads: dvc.yaml's train stage gives each family one thread (two
# trainings at once), the other stages run with 2 (the reference machine's cores) unless
# OMP_NUM_THREADS says otherwise; dvc.lock was made so.
demo: setup ## Run the whole pipeline (dvc repro): data, models, evaluation, Table II, robot, studies
	OMP_NUM_THREADS=$${OMP_NUM_THREADS:-2} dvc repro
	@for family in cvae avae_ts avae_ti muse; do \
		$(BIN)/python -m prg.commands.serving register models/$$family --evaluation reports/metrics.json || exit 1; \
	done
	@echo
	@echo "Dataset:  data/prepared/synthetic/ (train/val/test.npz, manifest.json, figures/)"
	@echo "Models:   models/<family>/model.ckpt and metrics.json  (dvc metrics show)"
	@echo "Serving:  registered as prg-<family> (alias champion) in mlruns.db: MLFLOW_TRACKING_URI=sqlite:///mlruns.db mlflow models serve -m models:/prg-muse@champion --env-manager local"
	@echo "Plots:    dvc plots show (training curves, coherence per class, robustness) -> dvc_plots/index.html"
	@echo "Reports:  reports/table1.md, coherence.md, robustness.md, likeness.md, styles.md, kinematics.md, figures/"
	@echo "Words:    reports/dictaphone/table2.png, table2.md; <word>/<sound|image>/word.rrd (rerun FILE)"
	@echo "Robot:    reports/simulate/ink.png, page.png, metrics.json; rerun reports/simulate/sim.rrd"
	@echo "Export:   reports/export/word.gcode, word.hpgl, word.svg (plotters), word.mcap, word.csv (arms)"
	@echo "Studies:  studies/turing/build/, studies/readability/build/: NOT READY while no human samples are"
	@echo "          given (human.dirs); writers record them with capture/index.html; index.html lists what is missing"
	@echo "Pilots:   studies/turing/pilot/index.html, studies/readability/pilot/index.html: PILOT copies that"
	@echo "          run end to end with held-out writers' words as the humans (try the pages; never for data);"
	@echo "          studies/turing/pilot/judge.json: prg-study judge's verdict before any participant"
	@echo "Analysis: reports/study/turing/report.html, reports/study/readability/report.html: on SIMULATED"
	@echo "          participants (prg-study simulate), each estimate shown beside the simulation's truth"
	@echo "Runs:     mlflow ui --backend-store-uri sqlite:///mlruns.db   then open"
	@echo "          http://127.0.0.1:5000/#/experiments/1/runs?workflowType=machine_learning (training runs;"
	@echo "          prg-tasks holds evaluate/write/simulate/dictaphone; UI: switch GenAI -> Model training)"
	@echo "Rerun:    rerun --web-viewer reports/simulate/sim.rrd   (or plain \`rerun FILE\` with a display)"
	@echo "Results:  make results SNAPSHOT=1   (the README's tables from these reports)"

# Families x seeds of the quick profile, evaluated per (seed, family) with the demo's budget
# (params.yaml evaluate:), then every table as mean and 95 % CI over seeds with paired,
# Holm-corrected comparisons (docs/results.md "Seeds and error bars"). Outputs under
# $(BASELINES)/ (ignored by git); one MLflow parent run holds the aggregate, each training run is
# its child. BASELINE_ARGS: Hydra overrides for training and evaluation (e.g. paths.data_dir=...),
# BASELINE_TRAIN_ARGS for training alone (e.g. trainer.max_epochs=1), BASELINE_EVAL_ARGS for
# evaluation alone (e.g. likelihood.n_test=50). BASELINE_JOBS trainings (joblib launcher) and
# evaluations run at once, each with cores/BASELINE_JOBS torch threads unless OMP_NUM_THREADS is set.
BASELINES ?= baselines
BASELINE_JOBS ?= 2
BASELINE_SEEDS ?= 0,1,2,3,4
BASELINE_FAMILIES ?= $(foreach f,cvae avae_ts avae_ti muse mvae mmvae mopoe,$(if $(wildcard conf/model/$(f).yaml),$(f)))
BASELINE_ARGS ?=
BASELINE_TRAIN_ARGS ?=
BASELINE_EVAL_ARGS ?=
_comma := ,
_empty :=
_space := $(_empty) $(_empty)
baselines: setup ## Families x 5 seeds (quick), evaluated; mean, 95 % CI, paired tests -> baselines/report/
	@set -e; started=$$(date +%s); out=$(abspath $(BASELINES)); \
	case "$(BASELINE_JOBS)" in ''|*[!0-9]*|0) echo "BASELINE_JOBS=$(BASELINE_JOBS): expected a whole number of at least 1" >&2; exit 2;; esac; \
	threads=$$(( $$(nproc) / $(BASELINE_JOBS) )); export OMP_NUM_THREADS=$${OMP_NUM_THREADS:-$$(( threads > 0 ? threads : 1 ))}; \
	parent=$$($(BIN)/python -m prg.commands.baselines parent $$out --started $$started $(BASELINE_ARGS)); \
	trap "$(BIN)/python -m prg.commands.baselines stopped '$$out' --started $$started" EXIT; \
	PRG_PARENT_RUN_ID=$$parent $(BIN)/prg-train -m \
		seed=$(BASELINE_SEEDS) model=$(subst $(_space),$(_comma),$(strip $(BASELINE_FAMILIES))) \
		experiment=quick 'export_dir='$$out'/seed$${seed}/$${model.name}' \
		'checkpoint_dir='$$out'/checkpoints/$${model.name}-seed$${seed}' \
		trainer.enable_progress_bar=false $(if $(filter-out 1,$(BASELINE_JOBS)),hydra/launcher=joblib \
		hydra.launcher.n_jobs=$(BASELINE_JOBS)) $(BASELINE_ARGS) $(BASELINE_TRAIN_ARGS); \
	$(BIN)/python -m prg.commands.baselines evaluate $$out --families "$(BASELINE_FAMILIES)" \
		--seeds $(BASELINE_SEEDS) --jobs $(BASELINE_JOBS) $(BASELINE_ARGS) $(BASELINE_EVAL_ARGS); \
	$(BIN)/python -m prg.commands.baselines aggregate $$out --families "$(BASELINE_FAMILIES)" \
		--seeds $(BASELINE_SEEDS) --started $$started $(BASELINE_ARGS); \
	echo "Reports: $(BASELINES)/report/index.md (tables, comparisons.csv, comparison.png)"

# Options after PAPER_ARGS=, e.g. PAPER_ARGS="--families muse --device auto" (python -m prg.commands.paper_scale -h)
paper: setup ## Paper scale on one GPU: the 4 families (experiment=paper) at once, then K=1000/5000 -> paper/
	$(BIN)/python -m prg.commands.paper_scale $(PAPER_ARGS)

# The whole split at K=1000/5000 takes ~70 min on 2 CPU cores (image cells): Table I on 100 test
# samples by default, coherence and robustness on the whole split; CONVERGED_ARGS= for all of it.
CONVERGED_ARGS ?= --n-test-likelihood 100
converged: setup ## Converged profile on this machine: the 4 families (experiment=converged), then K=1000/5000 -> converged/
	$(BIN)/python -m prg.commands.paper_scale --profile converged --device auto $(CONVERGED_ARGS)

test: setup ## Run the default test suite (fast; no `slow` tests)
	$(BIN)/pytest -m "not slow" -n 2 -q

test-all: setup ## Run every test, `slow` ones included
	$(BIN)/pytest -n 2 -q

docs: setup ## Build the documentation site offline (warnings are errors): docs/_build/html
	$(BIN)/sphinx-build -W --keep-going -q -b html docs docs/_build/html
	@echo "Docs: docs/_build/html/index.html"

lint: setup ## Check style with ruff
	$(BIN)/ruff check src studies tests benchmarks
	$(BIN)/ruff format --check src studies tests benchmarks

format: setup ## Format and fix with ruff
	$(BIN)/ruff format src studies tests benchmarks
	$(BIN)/ruff check --fix src studies tests benchmarks

# phi_S on voices and words nothing was tuned on: rescoring with one view, two, or as needed
SPEECH_ONLY = --only whisper+rescore "whisper+rescore 1 view" "whisper+rescore 2 views" \
	"whisper+rescore asks again"
SPEECH_OTHER_VOICES = --clean en-gb-x-rp+m3:120 \
	--hard en-gb-x-rp+m3:170 en-gb-scotland+f2:170 en+klatt4:175 $(SPEECH_ONLY)
SPEECH_OTHER_WORDS = --clean en-gb-x-rp+m3:120 en-us+Andy:120 \
	--hard en-us+Andy:170 en-gb-x-gbclan+f5:170 en-029+m2:170 $(SPEECH_ONLY) \
	--words ball,car,door,egg,hat,ice,king,lamp,moon,nose,pig,queen,rain,ship,toy,van,wolf,box,yard,zoo,baby,candle,dinner,engine,finger,guitar,island,jacket,ladder,monkey,number,ocean,pocket,rabbit,sister,tiger,violin,winter,zebra,picture

bench: setup ## Run the benchmarks (tables printed, JSON under benchmarks/results/), then `results`
	$(BIN)/python benchmarks/bench_prepare.py
	$(BIN)/python benchmarks/bench_train.py
	$(BIN)/python benchmarks/bench_evaluate.py
	$(BIN)/python benchmarks/bench_dmp.py
	$(BIN)/python benchmarks/bench_lasa.py
	$(BIN)/python benchmarks/bench_write.py --speech
	$(BIN)/python benchmarks/bench_connections.py
	$(BIN)/python benchmarks/bench_kinematics.py
	$(BIN)/python benchmarks/bench_speech.py
	$(BIN)/python benchmarks/bench_speech.py $(SPEECH_OTHER_VOICES) \
		--out benchmarks/results/bench_speech_other_voices.json
	$(BIN)/python benchmarks/bench_speech.py $(SPEECH_OTHER_WORDS) \
		--out benchmarks/results/bench_speech_other_words.json
	$(BIN)/python benchmarks/bench_simulate.py
	$(BIN)/python benchmarks/bench_startup.py
	$(MAKE) results

results: setup ## benchmarks/results.md and the docs pages' result tables from the JSON (after `make demo`: SNAPSHOT=1)
	$(BIN)/python benchmarks/summarize.py $(if $(SNAPSHOT),--snapshot)

# Mutation testing, not in CI: mutmut ([tool.mutmut] in pyproject.toml) mutates a copy of the
# numeric core under mutants/ and runs each mutant against the tests that reach the mutated function.
# All of it (~6000 mutants) took about 27 min on 2 shared cores; a part by mutant-name globs, e.g.
# MUTANTS='prg.pipeline.dmp*' or MUTANTS='prg.pipeline.* prg.models.fusion*' (8 min).
MUTANTS ?=
MUTATE_JOBS ?= 2
mutate: setup ## Mutation testing of the numeric core with mutmut (slow; not in CI): score per module
	rm -rf mutants
	OMP_NUM_THREADS=1 $(BIN)/mutmut run --max-children $(MUTATE_JOBS) $(foreach m,$(MUTANTS),'$(m)')
	@echo "per module: killed / timeout / survived (mutmut results: the survivors; mutmut show NAME)"
	@$(BIN)/mutmut results --all true | sed -nE 's/^ *([A-Za-z0-9_.]+)\.x[_ǁ][^:]*: (.+)$$/\1 \2/p' | \
		awk '{m[$$1]; c[$$1 " " $$2]++} END {for (k in m) { \
			n = c[k " killed"] + c[k " timeout"] + c[k " survived"] + c[k " no"]; if (!n) continue; \
			printf "  %-26s killed %4d  timeout %3d  survived %4d  no tests %3d  score %5.1f%%\n", \
			k, c[k " killed"], c[k " timeout"], c[k " survived"], c[k " no"], \
			100 * (c[k " killed"] + c[k " timeout"]) / n }}' | sort

constraints: setup ## Pin the .venv's package versions (all but torch and prg) into constraints.txt
	@{ echo "# Versions the project's results were made with (make constraints); pip install -c."; \
	  $(BIN)/pip freeze --exclude-editable | grep -viE '^(torch|prg)==' | LC_ALL=C sort -f; } > constraints.txt.tmp
	@mv constraints.txt.tmp constraints.txt && echo "constraints.txt: $$(grep -vc '^#' constraints.txt) packages"

clean: ## Remove caches (keeps .venv, data and runs)
	rm -rf .pytest_cache .ruff_cache .hypothesis
	find . -name __pycache__ -type d -prune -exec rm -rf {} +
