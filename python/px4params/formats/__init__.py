"""File formats of other tools, read and written in one place each: QGroundControl's ``.params``
files (``qgc_params``); the keys of documents read from files (``keys``)."""
