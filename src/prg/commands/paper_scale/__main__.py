"""``python -m prg.commands.paper_scale``: :func:`prg.commands.paper_scale.main`."""

from prg.commands.paper_scale.command import main

if __name__ == "__main__":  # importing the module (the API reference does) runs nothing
    main()
