"""The results tables of ``benchmarks/summarize.py``, one concept a module.

- :mod:`.common`: paths, the error, JSON reading, Markdown cells, the benchmark row.
- :mod:`.rows_models`, :mod:`.rows_writing`, :mod:`.rows_speech`: each benchmark's JSON as rows
  (ours against the reference measured in the same run).
- :mod:`.bench_table`: the benchmark table from those rows.
- :mod:`.snapshot`: copies of the demo's and the converged profile's metrics JSON.
- :mod:`.evaluation_tables`: Table I, coherence, robustness, smoothness, likeness from an
  evaluation's flat metrics.
- :mod:`.reports`: the demo pipeline's and the converged profile's sections.
- :mod:`.outputs`: ``benchmarks/results.md``, the docs pages' generated blocks and the CLI.
"""
