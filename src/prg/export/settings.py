"""The settings of an export: :class:`ExportSettings` and its plotter, G-code, HPGL and limit
settings.

Each single-number field declares the values it accepts (:func:`prg.fields.ranged`): the
dataclass checks them (:func:`prg.fields.check_fields`) and :data:`prg.checks.RANGES` takes its
``gcode.*``, ``hpgl.*`` and ``limits.*`` entries from them (:data:`prg.checks.DECLARED`). The
fields holding two numbers (``paper_mm``, ``position_mm``, ``origin_mm``, checked item by item),
:attr:`PlotterSettings.scale` (the top-level ``scale``) and :class:`ExportSettings`' own numbers
(the top-level ``tempo`` and ``sample_dt_s``) are checked against the constants of
:mod:`prg.checks` that its table gives those options (``plotter`` declares no range of its own).
This
module imports no numpy (nor the export modules that do), so that ``prg-export`` checks its
config before loading them; :mod:`prg.export.plotter`, :mod:`prg.export.limits` and
:mod:`prg.export.run`, which use these settings, export them too.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from prg.checks import (
    ORIGIN_MM,
    PAPER_MM,
    POSITION_MM,
    SAMPLE_DT_S,
    SCALE,
    TEMPO,
    Range,
    count,
    non_negative,
    positive,
    require_number,
)
from prg.errors import UsageError
from prg.fields import FromMapping, check, check_fields, checked, ranged, vector

if TYPE_CHECKING:
    from prg.export.limits import JointLimits
    from prg.sim import RobotSettings, SimSettings

__all__ = [
    "FILES",
    "FORMATS",
    "PEN_MODES",
    "UNITS",
    "ExportSettings",
    "GcodeSettings",
    "HpglSettings",
    "LimitSettings",
    "PlotterSettings",
    "check_formats",
]

FILES = {
    "gcode": "word.gcode",
    "hpgl": "word.hpgl",
    "svg": "word.svg",
    "mcap": "word.mcap",
    "csv": "word.csv",
}
FORMATS = tuple(FILES)

PEN_MODES = ("z", "servo")
UNITS = {"mm": ("G21", "millimetres", 1.0), "inch": ("G20", "inches", 1 / 25.4)}
# a servo command is one G-code word with its parameters, e.g. "M3 S1000", "M5", "M280 P0 S90"
_COMMAND = re.compile(r"^[GM]\d+(?: [A-Z][-+]?\d+(?:\.\d+)?)*$")


def check_formats(formats: Any) -> tuple[str, ...]:
    """``formats`` as a tuple of known format names (one name alone is accepted)."""
    if isinstance(formats, str):
        formats = [formats]
    if not isinstance(formats, Sequence) or not formats:
        raise UsageError(f"formats must be a list of {', '.join(FORMATS)}, got {formats!r}")
    names = []
    for name in formats:
        if name not in FORMATS:
            raise UsageError(f"formats: unknown format {name!r}: accepted are {', '.join(FORMATS)}")
        if name not in names:
            names.append(name)
    return tuple(names)


def _pair(settings: Any, name: str, problem: str, spec: Range) -> None:
    """Store the field ``name`` as two floats (else: ``PROBLEM, got ...``), each within ``spec``
    (named ``name[i]``), the item-by-item check of the option's entry in :data:`prg.checks.TABLE`."""
    values = vector(getattr(settings, name), name, 2, problem)  # numpy: imported when checked
    object.__setattr__(settings, name, values)
    for i, value in enumerate(values):
        require_number(value, f"{name}[{i}]", spec)


@dataclass(frozen=True)
class PlotterSettings(FromMapping):
    """The sheet on the plotter and where the word goes on it.

    Attributes
    ----------
    paper_mm : tuple of float
        Width (x, along the writing line) and height of the sheet (mm); A4 landscape by default.
    position_mm : tuple of float or None
        Lower-left corner of the word's ink bounding box on the sheet (mm from the sheet's
        lower-left corner); None: the word is centred.
    scale : float
        The word's size on paper relative to its own (cm) size (the top-level ``scale``, whose
        range :data:`prg.checks.SCALE` it is checked against).
    """

    paper_mm: tuple[float, float] = (297.0, 210.0)
    position_mm: tuple[float, float] | None = None
    scale: float = checked(1.0, require_number, spec=SCALE)

    def __post_init__(self) -> None:
        _pair(self, "paper_mm", "must be two positive numbers (mm)", PAPER_MM)
        if self.position_mm is not None:
            _pair(self, "position_mm", "must be two numbers (mm) or null", POSITION_MM)
        check_fields(self)


@dataclass(frozen=True)
class GcodeSettings(FromMapping):
    """G-code for a GRBL pen plotter.

    Attributes
    ----------
    origin_mm : tuple of float
        Machine coordinates (work coordinates of the program) of the sheet's lower-left corner.
    pen : str
        ``z``: the pen is lowered and raised by Z moves; ``servo``: by ``servo_down`` and
        ``servo_up`` commands (each followed by a ``G4`` wait of ``servo_wait_s``).
    z_up_mm, z_down_mm : float
        Z of the pen up and down (``z_up_mm`` > ``z_down_mm``).
    z_feed_mm_min : float
        Feed of the pen-down Z move (the pen-up move is rapid, ``G0``).
    servo_down, servo_up : str
        The servo commands (one G-code word with parameters: ``M3 S1000``, ``M5``).
    servo_wait_s : float
        Dwell after each servo command, for the pen to settle.
    max_feed_mm_min : float or None
        The machine's fastest feed (GRBL ``$110``/``$111``); a word that needs more is refused
        (GRBL would clamp it and write slower than planned). None: not checked.
    decimals : int
        Decimals of the coordinates in ``units`` (3: micrometres in mm; give 4 or more for
        inches).
    units : str
        ``mm`` (``G21``) or ``inch`` (``G20``): the unit of the program's coordinates and feeds;
        the settings above stay in millimetres.
    """

    origin_mm: tuple[float, float] = (0.0, 0.0)
    pen: str = "z"
    z_up_mm: float = ranged(5.0, Range(-1000, 1000))
    z_down_mm: float = ranged(0.0, Range(-1000, 1000))
    z_feed_mm_min: float = ranged(1000.0, positive(1_000_000))
    servo_down: str = "M3 S1000"
    servo_up: str = "M5"
    servo_wait_s: float = ranged(0.2, non_negative(60))
    max_feed_mm_min: float | None = ranged(None, Range(0, 1_000_000, low_open=True, optional=True))
    decimals: int = ranged(3, count(2, 6))
    units: str = "mm"

    def __post_init__(self) -> None:
        _pair(self, "origin_mm", "must be two numbers (mm)", ORIGIN_MM)
        check_fields(self)
        check(self.pen in PEN_MODES, "pen", f"must be {' or '.join(PEN_MODES)}, got {self.pen!r}")
        check(self.units in UNITS, "units", f"must be {' or '.join(UNITS)}, got {self.units!r}")
        check(
            self.z_up_mm > self.z_down_mm,
            "z_up_mm",
            f"must be above z_down_mm ({self.z_down_mm:g}), got {self.z_up_mm!r}",
        )
        for name in ("servo_down", "servo_up"):
            value = getattr(self, name)
            check(
                isinstance(value, str) and bool(_COMMAND.match(value)),
                name,
                f"must be one G-code command such as 'M3 S1000' or 'M5', got {value!r}",
            )


@dataclass(frozen=True)
class HpglSettings(FromMapping):
    """HPGL through vpype's device profiles.

    Attributes
    ----------
    device : str
        A plotter vpype knows (``hp7475a``, ``hp7440a``, ``hp7550``, ``dxy``, ``sketchmate`` ...).
    page : str or None
        One of the device's paper names (``a4``, ``a3``, ``letter`` ...); None: the one of
        ``plotter.paper_mm``'s size.
    absolute : bool
        Absolute coordinates (``PA``) throughout, else relative (``PR``, vpype's default).
    velocity : int or None
        Pen speed (``VS``, cm/s); None: the plotter's own.
    """

    device: str = "hp7475a"
    page: str | None = None
    absolute: bool = True
    velocity: int | None = ranged(None, count(1, 100, optional=True))

    def __post_init__(self) -> None:
        check(isinstance(self.device, str) and bool(self.device), "device", "must be a device name")
        check(
            self.page is None or isinstance(self.page, str), "page", "must be a paper name or null"
        )
        check(
            isinstance(self.absolute, bool),
            "absolute",
            f"must be true or false, got {self.absolute!r}",
        )
        check_fields(self)


@dataclass(frozen=True)
class LimitSettings(FromMapping):
    """How strict the check before a robot export is.

    Attributes
    ----------
    max_slow_down : float
        The largest uniform slow-down of the timing accepted (1: none; the trajectory must fit
        as planned).
    contact_above_mm : float or None
        A pen-down waypoint may be at most this far above the paper; None: the simulator's
        contact band (``control.contact_band_mm``).
    compliance_mm : float or None
        No waypoint may be further than this below the paper surface; None: the contact band.
    """

    max_slow_down: float = ranged(4.0, Range(1, 1000))
    contact_above_mm: float | None = ranged(None, Range(0, 100, optional=True))
    compliance_mm: float | None = ranged(None, Range(0, 100, optional=True))

    def __post_init__(self) -> None:
        check_fields(self)


@dataclass(frozen=True)
class ExportSettings:
    """What to export and how.

    Attributes
    ----------
    formats : tuple of str
        Any of ``gcode``, ``hpgl``, ``svg`` (pen plotters) and ``mcap``, ``csv`` (robot arms).
    tempo : float
        Multiplies the DMP's duration for the plotter (2: twice as slow); the arm's is
        ``sim.tempo``.
    sample_dt_s : float
        Spacing of the DMP rollout the G-code follows (one move per step).
    plotter, gcode, hpgl : PlotterSettings, GcodeSettings, HpglSettings
    robot : RobotSettings or None
        The arm (robot formats); None: the Panda of ``conf/robot/panda.yaml``.
    sim : SimSettings or None
        The simulation that computes the arm's trajectory (paper, placement, motion, IK ...);
        None: ``conf/simulate.yaml``'s defaults.
    limits : LimitSettings
    datasheets : mapping of str to mapping
        Per robot name, its datasheet limits (:meth:`JointLimits.from_mapping
        <prg.export.limits.JointLimits.from_mapping>`); a robot without one is checked against
        its URDF alone.

    Notes
    -----
    ``tempo`` and ``sample_dt_s`` are top-level keys of ``conf/export.yaml`` (``tempo`` shared
    with ``prg-simulate``): they are declared with the constants :data:`prg.checks.TEMPO` and
    :data:`prg.checks.SAMPLE_DT_S` that the table gives those options.
    """

    formats: tuple[str, ...] = FORMATS
    tempo: float = ranged(1.0, TEMPO)
    sample_dt_s: float = ranged(0.01, SAMPLE_DT_S)
    plotter: PlotterSettings = field(default_factory=PlotterSettings)
    gcode: GcodeSettings = field(default_factory=GcodeSettings)
    hpgl: HpglSettings = field(default_factory=HpglSettings)
    robot: RobotSettings | None = None
    sim: SimSettings | None = None
    limits: LimitSettings = field(default_factory=LimitSettings)
    datasheets: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "formats", check_formats(self.formats))
        check_fields(self)
        check(isinstance(self.datasheets, Mapping), "datasheets", "must map robot names to limits")

    def datasheet(self, robot: RobotSettings) -> JointLimits | None:
        """The datasheet limits of ``robot`` (None if there are none)."""
        node = self.datasheets.get(robot.name)
        if node is None:
            return None
        from prg.errors import SettingsError
        from prg.export.limits import JointLimits  # numpy: imported when a datasheet is read

        try:
            return JointLimits.from_mapping(robot.arm_joints, node)
        except SettingsError as err:
            raise err.under(f"limits.joints.{robot.name}") from None
