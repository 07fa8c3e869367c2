"""DSDL types: loading (pydsdl, pydronecan) into a cached model (``loader``), DroneCAN data type
signatures (``signature``) and the compiled schema API (``schema``: encode, decode, leaves)."""
