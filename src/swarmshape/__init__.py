"""swarmshape: a swarm of square robots organises itself into a shape given as a bitmap."""

import os

os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")  # keep pygame's banner off our output
