"""One module per command (or family of commands); see the registry in ``cli/main.py``."""
