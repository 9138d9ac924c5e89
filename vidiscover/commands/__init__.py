"""Command modules of the ``vidiscover`` CLI, imported lazily by :mod:`vidiscover.cli`.

Each module defines click commands that use :func:`vidiscover.cli.handle_errors`
and :func:`vidiscover.cli.emit`; :data:`vidiscover.cli.LAZY_COMMANDS` lists them.
"""
