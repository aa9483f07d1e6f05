"""pytest glue for pytest-emrd (being built: see issue 5)."""
