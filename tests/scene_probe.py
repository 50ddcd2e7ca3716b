"""Reads what the page really draws, from its own three.js scene.

three.js announces every scene and renderer it creates to a devtools hook,
``window.__THREE_DEVTOOLS__``, if the page defines one. :data:`INIT_SCRIPT`
defines it before the page loads (``page.add_init_script``), keeps the scenes,
and, while recording, samples the nodes the sandbox draws each time a scene
is about to be rendered: the state of every frame the viewer sees.

Nodes are found by their height above the floor (sandbox.app.view.scene's Z_*
constants, three.js's y in the page), which is unique per kind of node.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sandbox.app.view import scene

#: Height -> name of the nodes the probe reads (point clouds and batched meshes).
NODES = {"lit": scene.Z_LIT, "boxes": scene.Z_BOXES, "robots": scene.Z_ROBOTS}

INIT_SCRIPT = """
(() => {
  const NODES = %(nodes)s;
  const probe = window.__sandboxProbe = {scenes: [], samples: [], recording: false, max: 4000, frames: 0};
  const hook = new EventTarget();
  hook.addEventListener('observe', (event) => {
    const o = event.detail;
    if (!o || !o.isScene) return;
    probe.scenes.push(o);
    const before = o.onBeforeRender;
    o.onBeforeRender = function (...args) {
      probe.frames += 1;
      if (probe.recording && probe.samples.length < probe.max) {
        const sample = probe.read(o);
        if (sample) probe.samples.push(sample);
      }
      return before.apply(this, args);
    };
  });
  window.__THREE_DEVTOOLS__ = hook;

  // The drawn objects of each node: point clouds, or the instanced meshes of batched meshes (one per
  // chunk of the boxes), with their local x, y (and, for a mesh instance, its turn about z).
  probe.find = (scene) => {
    const found = {};
    scene.traverse((o) => {
      if (!(o.isPoints || o.isInstancedMesh2 || o.isMesh)) return;
      const v = o.position.clone();
      o.getWorldPosition(v);
      for (const [name, z] of Object.entries(NODES)) {
        if (Math.abs(v.y - z) < 1e-4) (found[name] = found[name] || []).push(o);
      }
    });
    return found;
  };
  const shown = (o) => { for (let p = o; p; p = p.parent) if (!p.visible) return false; return true; };
  probe.xy = (objects) => {
    const out = [];
    for (const o of objects || []) {
      if (!shown(o)) continue;
      if (o.isInstancedMesh2) {
        for (let i = 0; i < o.instancesCount; i++) {
          const m = o.getMatrixAt(i).elements;
          out.push([m[12], m[13], Math.atan2(m[1], m[0])]);
        }
      } else if (o.isPoints) {
        const a = o.geometry.attributes.position;
        for (let i = 0; i < a.count; i++) out.push([a.getX(i), a.getY(i)]);
      }
    }
    return out;
  };
  probe.read = (scene) => {
    const nodes = probe.find(scene);
    if (!nodes.robots) return null;
    const sample = {t: performance.now()};
    for (const name of Object.keys(NODES)) sample[name] = probe.xy(nodes[name]);
    return sample;
  };
})();
""" % {"nodes": "{" + ", ".join(f"{k!r}: {v}" for k, v in NODES.items()) + "}"}


def start(page: Any) -> None:
    page.evaluate("() => { window.__sandboxProbe.samples = []; window.__sandboxProbe.recording = true; }")


def stop(page: Any) -> list[dict]:
    """The samples since :func:`start`, one per rendered frame."""
    return page.evaluate("() => { window.__sandboxProbe.recording = false; return window.__sandboxProbe.samples; }")


def samples_taken(page: Any) -> int:
    """How many frames :func:`start` has recorded so far."""
    return int(page.evaluate("() => window.__sandboxProbe.samples.length"))


def frames_rendered(page: Any) -> int:
    return int(page.evaluate("() => window.__sandboxProbe.frames"))


def now(page: Any) -> dict:
    """The drawn state right now (the last rendered frame's nodes)."""
    return page.evaluate("() => { const p = window.__sandboxProbe; for (const s of p.scenes) { "
                         "const r = p.read(s); if (r) return r; } return null; }")


def array(sample: dict, name: str) -> np.ndarray:
    rows = sample.get(name) or []
    return np.asarray(rows, dtype=float).reshape(len(rows), -1)
