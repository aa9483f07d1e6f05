"""world stage of pytest-emrd."""
