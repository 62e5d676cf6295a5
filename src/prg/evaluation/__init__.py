"""Evaluation: importance-weighted log-likelihoods (Table I), coherence, robustness."""
