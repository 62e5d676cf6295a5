"""Helpers shared by several test modules (not fixtures of the whole suite: those are in
``tests/conftest.py``). ``browser`` drives the study pages; the others hold the helpers and
fixtures of tests that were split by the module they exercise, named after the topic."""
