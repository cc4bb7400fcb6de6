"""The subcommands of ``spherecal``: one module each, with ``HELP``, ``add_arguments(parser)`` and ``run(args)``.

This is the command-line layer: it may import every package; no library module imports it.
"""
