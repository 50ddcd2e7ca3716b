"""The Population and physics folder's tooltips: at most two short lines of
plain words each. The full reference of every value (formulas, where the
paper's text and the authors' program differ) stays in its declaration in
:mod:`sandbox.model.config`, which ``phototaxis run --help`` and docs/cli.md
show. Constant text; any thread."""

from __future__ import annotations

#: The choices' words are the dropdown's own; a tooltip names them when a student must pick one.
TIPS = {
    # Model
    "profile": "Which model to follow: the authors' released program (it made the paper's tables) or the "
               "paper's written text. Sets the values below on reset.",
    # Arena
    "arena_size": "Width of the square floor the robots live on.",
    "construction_size": "Width of the square in the middle where the shape is built. Its wall stops "
                         "boxes but not robots.",
    "robot_spawn_size": "Width of the square the robots start in, around the construction area.",
    "assembly_centre": "Where the goal sits: on a light ('light') or between four lights ('arena').",
    "dt": "Time one step of the physics stands for. Shorter is finer and slower.",
    # Population and bodies
    "robots": "How many robots there are.",
    "robot_radius": "Size of a robot (its radius).",
    "robot_density": "How heavy a robot is for its size: heavier robots push harder.",
    "robot_friction": "How much robots grip what they rub against.",
    "robot_elasticity": "How much robots bounce off things (0: not at all).",
    "boxes": "How many hexagonal boxes there are to push into the goal.",
    "box_size": "Size of a box; 'box size is' says whether it is the centre-to-side or centre-to-corner "
                "distance.",
    "box_size_is": "What 'box size' measures: centre to side ('apothem', the paper) or centre to corner "
                   "('circumradius', the authors' program).",
    "box_start": "Where boxes start: scattered over the construction area (the paper) or already packed "
                 "into the goal.",
    "box_density": "How heavy a box is for its size.",
    "box_friction": "How much boxes grip what they rub against.",
    "box_elasticity": "How much boxes bounce off things (0: not at all).",
    "box_skin": "A thin rounded layer around each box for collisions, as the authors' physics engine "
                "gives every shape.",
    "wall_friction": "How much bodies grip the walls.",
    "box_damping": "How fast a box stops once nothing pushes it: higher stops sooner.",
    "box_damping_model": "The formula that slows the boxes: the paper's ('exponential') or the authors' "
                         "physics engine's ('box2d').",
    # Light grid
    "light_pitch": "Distance between neighbouring lights in the overhead grid.",
    "light_height": "How high the lights hang above the floor: higher lights spread wider and dimmer.",
    "light_falloff": "How fast a light dims with distance: 2 dims with the square of the distance.",
    "light_angle": "How a light's brightness depends on the angle it shines at: the paper's rule or the "
                   "authors' program's.",
    "light_range": "Lights farther than this across or along do not reach a point.",
    "light_window": "Which lights reach a point: those within 'light range' (the paper) or a fixed block "
                    "of cells around it (the authors' program).",
    "light_intensity": "How bright a light is when it is on.",
    "field_samples": "How finely the light on the floor is sampled between lights: finer is slower to "
                     "change.",
    # Robot: gains and energy
    "sensor_offset": "How far each of the four light sensors sits from the robot's centre.",
    "photocells": "Where the four light sensors sit: front, back, left and right ('axes') or at four "
                  "corners ('corners').",
    "steering": "Which sensors steer: every sensor on each side ('sides') or only the front pair "
                "('front').",
    "k_drive": "How fast a robot drives towards brighter light: the difference front minus back, times "
               "this.",
    "k_turn": "How fast a robot turns towards brighter light: the difference left minus right, times this.",
    "command_period": "How many steps a robot keeps going before it reads its sensors again.",
    "motor": "How a command moves the robot: set as its speed every step ('continuous') or given as one "
             "push that then coasts ('set-once').",
    "eta_in": "How much charge a robot gains from the light it stands in.",
    "metabolic": "Charge a robot spends every step just to stay alive.",
    "eta_out": "Charge a robot spends for moving: faster costs more.",
    "energy_turn_cost": "What moving costs: the commanded speed and turn ('absolute') or the motion the "
                        "robot really makes ('signed').",
    "capacity": "Most charge a robot can store.",
    "start_charge": "Charge every robot has at the start.",
    # Controller cycle
    "update_every": "Steps between two changes of the lit outline.",
    "scale_rate": "How much the outline shrinks at each change while contracting: 0.975 shrinks it by "
                  "2.5 %.",
    "size_schedule": "How the outline's size moves between its smallest and largest: the paper's rule "
                     "('clamped') or the authors' program's ('program').",
    "hold_steps": "How long the smallest outline stays lit before it grows back.",
    "min_size_rule": "How small the outline gets: from the goal's area ('equal-area', the paper) or from "
                     "its inner circle ('inradius', the authors' program).",
    "band": "How wide the lit band is: a light is on when it is this close to the outline.",
    "circle_max": "Largest circle outline, as a share of half the arena's width.",
    "polygon_max_area": "Largest outline of a shape, as a share of the arena's area.",
    "polygon_max_rule": "How the largest outline of a shape is found: the largest that fits ('fit', the "
                        "paper) or grown step by step ('grow', the authors' program).",
    "flare_mode": "How Flare pushes corners out: the goal's sharp corners (the paper) or every corner of "
                  "the lit outline (the authors' program).",
    "switch_mode": "When Switch to circle takes over: at a share of the way, both ways (the paper), or only "
                   "while growing (the authors' program).",
    "outline": "The outline the light follows: the goal scaled ('scaled', the paper) or grown all round "
               "('offset', any shape); 'auto' scales roundish goals only.",
    "notches": "On a shape with narrow notches, light them while the band closes in so the robots keep them "
               "clear ('lit'), or leave the band alone ('plain').",
    "gather": "On a shape whose notches open both ways (an H, a K), light only the starved sides as the band "
              "grows, so the robots come back there ('auto'), or the whole band ('off').",
    "no_corners_count": "How No corners counts the lights it leaves dark: rounded (the paper) or at least "
                        "that share (the authors' program).",
    # Run
    "seed": "The random start. The same seed and settings give the same run.",
    "metrics_every": "Steps between two points on the charts.",
    # Physics engine
    "iterations": "How hard the physics works to keep bodies from overlapping: more is firmer and slower.",
    "threads": "Processor threads the physics uses (1 or 2).",
    "collision_slop": "How far bodies may overlap before the physics pushes them apart.",
    "sleep_time": "A still pile of bodies stops being computed after this long, until something touches "
                  "it (0: never).",
    "idle_speed": "Below this speed a body counts as still (for 'sleep time').",
}


def tip(name: str, applies_on_reset: bool) -> str:
    """The tooltip of parameter ``name``, with when a change takes effect."""
    return TIPS[name] + (" Applies on Reset." if applies_on_reset else " Applies at once.")
