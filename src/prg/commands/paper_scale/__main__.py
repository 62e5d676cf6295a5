"""``python -m prg.commands.paper_scale``: :func:`prg.commands.paper_scale.main`."""

from prg.commands.paper_scale.command import main

main()
