"""prg: Perceive-Represent-Generate, from multimodal commands to robot handwriting."""

__version__ = "0.1.0"
