"""``python -m prg.serving register EXPORT_DIR [--evaluation JSON]`` (prg.serving.main)."""

import sys

from prg.serving import main

sys.exit(main())
