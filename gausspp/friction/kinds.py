"""The modes of a frictional contact, as the records name them."""

OPEN, STICK, SLIDE = "open", "stick", "slide"
#: A bilateral row kept among the contacts (``gp.simulate``'s friction lane): always closed, its force of either sign.
HELD = "held"
