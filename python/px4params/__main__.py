"""``python -m px4params`` is the ``px4params`` command."""

from px4params.cli.main import main

raise SystemExit(main())
