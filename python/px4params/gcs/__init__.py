"""For ground stations and firmware: ``parameters.json`` metadata (``metadata``), the C header
(``cheader``) and a metadata-only codec a ground station can copy (``codec``)."""
