"""The controller's phases: the band contracts to the smallest outline, holds
it, dilates, and the cycle repeats."""

CONTRACTING, HOLDING, DILATING = "contracting", "holding", "dilating"
