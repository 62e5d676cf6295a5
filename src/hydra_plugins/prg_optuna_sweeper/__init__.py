"""A Hydra sweeper that searches with Optuna (``hydra/sweeper=prg_optuna``), for ``prg-train``.

Why not the PyPI plugin ``hydra-optuna-sweeper``: its newest release (1.3.0) requires
``optuna<3``, whose SQLite storage does not work with SQLAlchemy 2 (which MLflow 3 requires) and
which ``optuna-dashboard`` does not open; the upstream port to Optuna 4 is merged but not released
on PyPI. This sweeper uses the current Optuna API (``study.ask`` / ``study.tell``) and Hydra's
own sweep grammar, and is small: the sampling is Optuna's, the job launching Hydra's launcher's.
"""
