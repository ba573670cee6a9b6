"""The one palette every figure of the project draws with (the app's plots, the flight report): Paul Tol's
colour-blind-safe "muted" scheme with black and his "vibrant" orange, by name. An estimator names its colour
(``estimation.About.colour``; ``estimation.colour_of`` looks it up here), so it is the same colour in every plot
of the app and every figure of the report; the aircraft's own estimate is wine and a simulator's truth black (both dashed beneath the estimates).
No Qt here: the report and the exports import it too."""

from __future__ import annotations

# Tol's "muted" (nine colours told apart by colour-blind readers and on white), with black and the orange of his
# "vibrant" palette, which differs from all nine: eleven curves, by Tol's names.
PALETTE = {"indigo": "#332288", "wine": "#882255", "green": "#117733", "teal": "#44AA99", "rose": "#CC6677",
           "olive": "#999933", "cyan": "#88CCEE", "sand": "#DDCC77", "purple": "#AA4499", "black": "#000000",
           "orange": "#EE7733"}
ONBOARD_COLOUR = PALETTE["wine"]
TRUTH_COLOUR = "#000000"  # dashed black, as the figures draw truth
UNNAMED_COLOUR = "#444444"  # an estimator naming none of the palette's colours (``estimation.colour_of``)
# A flight log's sections (``autopilot.sections``): what the controller had is its own estimate, in the aircraft's
# colour; what it asked for, a blue no estimator takes.
DESIRED_COLOUR, ACTUAL_COLOUR = "#1f5fbf", ONBOARD_COLOUR

