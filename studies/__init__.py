"""User-study toolkit (human vs robot handwriting): design, stimuli, web bundles, analysis."""
