"""The parameter store: which types are parameters (``spec``), classic parameters (``classic``),
the store itself (``store``), its file (``file``), destructured flat names (``flat``), QGC
``.params``/JSON files (``paramfile``) and a locked session on the store file (``session``)."""
