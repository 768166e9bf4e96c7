"""How many runs compare mode holds at once (each has a colour of its own): a plain value, without
numpy or Qt, so that ``rollball-app`` refuses a longer ``--compare`` at once (``main.py``)."""

MAX_RUNS = 6
