"""report stage of pytest-emrd."""
