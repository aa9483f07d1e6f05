"""metrics stage of pytest-emrd."""
