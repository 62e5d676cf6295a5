"""End-to-end tests: whole workflows across processes and tools: Hydra multiruns and sweeps,
DDP scale-out, kill and resume, the paper-scale runner, DVC pipelines, MLflow serving over HTTP,
the study pages in a headless browser (Playwright, helpers in ``tests/helpers/browser.py``), the
README's snippet, reproducible builds in fresh processes."""
