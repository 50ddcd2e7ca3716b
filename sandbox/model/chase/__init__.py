"""Chase: a closed loop of ours, built on the paper's controller.

The paper's controller scales the goal about its centre. Near the goal that
leaves the band far beyond a star's tips (scaling by (r + 0.5) / r moves a
tip out by 0.5 R / r, over a metre) while it touches the notches, so the tips
stay empty. And it never knows where boxes spill out or where the goal still
lacks them. With *chase* the controller sees the boxes, as an overhead camera
would, and does five things the open loop cannot:

1. **Offsets, not scales** (:mod:`.sculpt`). The outline is the goal grown
   by a distance ``t`` (round corners), so near the goal the band is the
   same distance from every part of it. The controller's size still sets it:
   ``t`` is how far the sized outline lies beyond the goal-sized one, so the
   smallest outline is one robot diameter from the goal all round.
2. **Turning early** (:mod:`.sight`). A dilation turns back once the
   outline is ``chase`` metres beyond the farthest box outside the goal.
3. **Sculpting** (:mod:`.sculpt`). Within ``Sculpting.start`` of the goal,
   every point of the band looks at the goal edge nearest it. Where boxes
   spill out there, the band moves in by ``press`` (robots push them back);
   where the goal lacks boxes and none spill, the band's lights go dark, so
   the robots leave and the pressed pile can flow in.
4. **Patience** (:mod:`.hold`). The smallest outline is held, re-sculpted
   every update, while boxes keep arriving in the goal, and for as long as
   nearly every stray box is within the robots' reach; it lets go only to
   fetch boxes that are out of reach. Each dilation costs boxes: robots that
   worked their way into the pile drive out through it.
5. **Finishing** (:mod:`.finish`). A run is measured at its last step, and
   it should end in a hold: the fraction in the goal is highest there. Every
   dilation turns back early enough for the contraction to reach the
   smallest outline, with the shortest hold to spare, before the run is
   measured. When one more cycle out to the farthest stray box and back fits
   but not two, the hold waits so that the last cycle ends just before the
   end, with the far boxes swept in. When no whole cycle fits it still lets
   go, and the cut-short cycle fetches what a long hold squeezes out: the
   robots' crowd on the band is up to 2 m deep, and over thousands of steps
   it pushes stray boxes to its outer edge.

:class:`ChaseController` (:mod:`.controller`) is the paper's controller with
these in its hooks; its numbers are :mod:`.tuning`'s.
"""

from sandbox.model.chase.controller import ChaseController

__all__ = ["ChaseController"]
