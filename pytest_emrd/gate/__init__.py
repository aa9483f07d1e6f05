"""gate stage of pytest-emrd."""
