"""Function objects (registered in the ``functionObject`` family)."""
