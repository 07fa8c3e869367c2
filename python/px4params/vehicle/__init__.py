"""The vehicle: driver declarations (``drivers``), autostart from the manifest (``autostart``),
simulated hardware to boot it on (``simbench``) and its SVG timeline (``timeline``), PX4 device
IDs (``devid``), what PX4's boards start on their own (``boards``)."""
