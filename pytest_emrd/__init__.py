"""pytest-emrd: Explore, Map, Remember, Decide — a pytest plugin and benchmark suite for
embodied vision-language models in a safety-critical evacuation scenario."""

__version__ = "0.1.0"
