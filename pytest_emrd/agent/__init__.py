"""agent stage of pytest-emrd."""
