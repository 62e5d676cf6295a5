"""The command layer: each module wires a Hydra config to one library call and its outputs."""
