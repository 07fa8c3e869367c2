"""``px4params gui``: a ground-station page for the manifest, served on loopback (``app``), over
a vehicle on MAVLink or a store file (``vehicle``), with parameter files read into a review and
written back (``files``); the page itself is ``static/`` (plain HTML, CSS and JavaScript)."""
