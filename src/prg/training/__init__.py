"""Training support: Lightning callbacks and the generation figures they log."""
