"""NSH, PX4's shell, as far as parameters go: the ``param`` verbs (``param``) and airframe files
of ``param`` lines (``airframe``)."""
