"""`python -m px4params` is the `px4params` command."""

from .cli import main

raise SystemExit(main())
