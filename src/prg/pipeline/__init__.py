"""The writing pipeline: from a generated word to a robot trajectory (DMPs, connection, timing)."""
