"""``python -m prg.tracking move-store ...`` / ``log-pending FILE``, the name the background
runs' logger (:func:`prg.tracking.hand_off_run`) and the README use: runs the command line of
:mod:`prg.commands.tracking`, named as a string and loaded only when this entry point runs, so
importing :mod:`prg.tracking` never loads the command layer."""

import runpy

if __name__ == "__main__":
    runpy.run_module("prg.commands.tracking", run_name="__main__", alter_sys=True)
