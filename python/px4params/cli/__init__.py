"""The ``px4params`` command line: ``main.py`` parses and dispatches, ``status.py`` holds the
exit codes, and each module of ``commands/`` is one command, imported only when it runs."""
