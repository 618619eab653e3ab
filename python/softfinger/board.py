"""The driver board from Python: the console contract (docs/console.md) over a serial port (pyserial),
the simulated board (finger-sim, a child process) or the firmware's emulator image (QEMU, its
console on a local TCP socket that pyserial opens as ``socket://``).

One command at a time, each answered within a time-out: an ``err <code>: <message>`` reply
raises :class:`BoardError`, a board that stops answering raises :class:`BoardTimeout`, a link
that closes raises :class:`BoardLinkError`; nothing waits forever. A :class:`Board` is a
context manager: leaving the block (normally, by an exception or by Ctrl-C) sends ``stop``.

What it is not: the model (``softfinger.Finger``), nor a second console grammar: the board's
replies are read by the console protocol crate (``finger-protocol``, through the extension:
``key=value``, comma-separated components), the parser the firmware's tests and the ``finger``
client use.
Units as at the console: forces N, voltages V, lengths mm, angles degrees.
"""

from __future__ import annotations

import os
import queue
import shutil
import socket
import subprocess
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple, Union

import serial

from ._core import _reply_fields, _reply_final, _reply_measured

Value = Union[float, str, Tuple[float, ...]]

#: How much longer than its own duration a ``wait <s>`` reply may take.
WAIT_SLACK_S = 5.0


class BoardError(Exception):
    """The board refused a command: ``err <code>: <message>``.

    ``code`` is the console's error code (``unknown``, ``usage``, ``bad-number``, ``too-long``,
    ``limit``, ``not-armed``, ``armed``, ``unreachable``, ``fault``, or a newer one), ``message``
    its human text, ``command`` the line that was refused."""

    def __init__(self, code: str, message: str, command: str = ""):
        super().__init__(f"err {code}: {message}" + (f" (command: {command})" if command else ""))
        self.code = code
        self.message = message
        self.command = command


class BoardTimeout(TimeoutError):
    """No reply line from the board within the time-out (s)."""

    def __init__(self, command: str, timeout_s: float):
        super().__init__(f"the board did not answer {command!r} within {timeout_s:.1f} s")
        self.command = command
        self.timeout_s = timeout_s


class BoardLinkError(ConnectionError):
    """The link itself failed: it could not be opened, or the board's side closed."""


def parse_fields(line: str) -> Dict[str, Value]:
    """The ``key=value`` fields of an ``ok`` line: a number as a float, comma-separated numbers
    as a tuple, anything else as its text (read by the console protocol crate, through the
    extension: the project's one parser of the grammar)."""
    return _reply_fields(line)


def _tuple(v: Value) -> Tuple[float, ...]:
    if isinstance(v, tuple):
        return v
    if isinstance(v, float):
        return (v,)
    raise BoardLinkError(f"a number list was expected, got {v!r}")


def _float(v: Value) -> float:
    if isinstance(v, float):
        return v
    raise BoardLinkError(f"a number was expected, got {v!r}")


def _optional(f: Dict[str, Value], key: str) -> Optional[float]:
    """A number field a newer firmware adds (None when the reply lacks it)."""
    return _float(f[key]) if key in f else None


@dataclass(frozen=True)
class Status:
    """The board's ``status``: what it is doing now."""

    armed: bool
    #: cable tension target, N
    force_N: float
    #: channel voltages, V
    volts_V: Tuple[float, ...]
    #: stack thicknesses, mm
    thick_mm: Tuple[float, ...]
    #: joint angles, degrees
    joints_deg: Tuple[float, ...]
    #: tip pose: x mm, y mm, angle degrees
    tip: Tuple[float, ...]
    #: cable excursion, mm
    cable_mm: float
    #: servo angle, degrees
    servo_deg: float
    #: "none" or the fault's name
    fault: str
    #: the HV read-back (boards that have one; None otherwise): measured voltages, V
    vmeas_V: Optional[Tuple[float, ...]] = None
    #: each stack's return current, µA
    imeas_uA: Optional[Tuple[float, ...]] = None
    #: each stack's thickness sensed from its capacitance, mm (nan until measured)
    thick_meas_mm: Optional[Tuple[float, ...]] = None
    #: the orientation in force (firmware with gravity; None otherwise): gravity's magnitude,
    #: m/s² (0: off), and its direction, degrees from the straight finger's axis toward the
    #: cable side (0 hanging straight down)
    grav_m_s2: Optional[float] = None
    grav_dir_deg: Optional[float] = None
    #: every field of the reply, parsed (newer firmware may add some)
    fields: Dict[str, Value] = field(default_factory=dict, compare=False)

    @staticmethod
    def _measured(line: str, key: str) -> Optional[Tuple[float, ...]]:
        v = _reply_measured(line, key)
        return None if v is None else tuple(v)

    @classmethod
    def parse(cls, line: str) -> "Status":
        f = parse_fields(line)
        return cls(
            armed=_float(f["armed"]) != 0.0,
            force_N=_float(f["force"]),
            volts_V=_tuple(f["volts"]),
            thick_mm=_tuple(f["thick"]),
            joints_deg=_tuple(f["joints"]),
            tip=_tuple(f["tip"]),
            cable_mm=_float(f["cable"]),
            servo_deg=_float(f["servo"]),
            fault=str(f["fault"]),
            vmeas_V=cls._measured(line, "vmeas"),
            imeas_uA=cls._measured(line, "imeas"),
            thick_meas_mm=cls._measured(line, "thick_meas"),
            grav_m_s2=_optional(f, "grav"),
            grav_dir_deg=_optional(f, "grav_dir"),
            fields=f,
        )

    #: the CSV columns of :meth:`row`
    COLUMNS = ("armed", "force_N", "volts1_V", "volts2_V", "volts3_V", "thick1_mm", "thick2_mm", "thick3_mm",
               "joint1_deg", "joint2_deg", "joint3_deg", "tip_x_mm", "tip_y_mm", "tip_deg", "cable_mm", "servo_deg", "fault")

    def row(self) -> List[Union[float, int, str]]:
        """The status as one CSV row (columns :attr:`COLUMNS`)."""
        return [int(self.armed), self.force_N, *self.volts_V, *self.thick_mm, *self.joints_deg, *self.tip,
                self.cable_mm, self.servo_deg, self.fault]


@dataclass(frozen=True)
class Limits:
    """The board's ``limits``: the ceilings in force."""

    #: per-channel voltage ceiling, V (every commanded voltage stays below it)
    vmax_V: Tuple[float, ...]
    #: pull-in voltage of one layer (the 33 % limit), V
    vpullin_V: float
    #: HV supply maximum, V
    supply_V: float
    #: fraction of V_pi the ceiling allows
    margin: float
    #: the largest cable tension at the present voltages (end of the equilibrium branch), N;
    #: None when the board could not compute it
    fmax_N: Optional[float]
    #: the orientation in force, as :class:`Status`' (None: firmware without gravity)
    grav_m_s2: Optional[float] = None
    grav_dir_deg: Optional[float] = None
    #: every field of the reply, parsed
    fields: Dict[str, Value] = field(default_factory=dict, compare=False)

    @classmethod
    def parse(cls, line: str) -> "Limits":
        f = parse_fields(line)
        fmax = f.get("fmax")
        return cls(
            vmax_V=_tuple(f["vmax"]),
            vpullin_V=_float(f["vpullin"]),
            supply_V=_float(f["supply"]),
            margin=_float(f["margin"]),
            fmax_N=fmax if isinstance(fmax, float) else None,
            grav_m_s2=_optional(f, "grav"),
            grav_dir_deg=_optional(f, "grav_dir"),
            fields=f,
        )


@dataclass(frozen=True)
class BoardSolution:
    """The board's ``solve``: its own model (f32) at a tension and voltages; nothing moves."""

    #: joint angles, degrees
    joints_deg: Tuple[float, ...]
    #: tip pose: x mm, y mm, angle degrees
    tip: Tuple[float, ...]
    #: cable excursion, mm
    cable_mm: float
    #: stack thicknesses (relaxed), mm
    thick_mm: Tuple[float, ...]
    #: tip stiffness diagonal: k_xx N/mm, k_yy N/mm, k_θθ N·mm/rad
    stiffness: Tuple[float, ...]
    #: solver iterations (0: the board's branch table answered)
    iters: int
    #: every field of the reply, parsed
    fields: Dict[str, Value] = field(default_factory=dict, compare=False)

    @classmethod
    def parse(cls, line: str) -> "BoardSolution":
        f = parse_fields(line)
        return cls(
            joints_deg=_tuple(f["joints"]),
            tip=_tuple(f["tip"]),
            cable_mm=_float(f["cable"]),
            thick_mm=_tuple(f["thick"]),
            stiffness=_tuple(f["stiffness"]),
            iters=int(_float(f["iters"])),
            fields=f,
        )


@dataclass(frozen=True)
class Force:
    """The board's ``force``: the tension target and where the servo goes for it."""

    #: cable tension target, N
    force_N: float
    #: cable the servo pulls in, mm
    cable_mm: float
    #: servo angle, degrees
    servo_deg: float
    #: every field of the reply, parsed
    fields: Dict[str, Value] = field(default_factory=dict, compare=False)

    @classmethod
    def parse(cls, line: str) -> "Force":
        f = parse_fields(line)
        return cls(force_N=_float(f["force"]), cable_mm=_float(f["cable"]), servo_deg=_float(f["servo"]), fields=f)


@dataclass(frozen=True)
class Pose:
    """The board's ``pose``: the inverse's tension and voltages for joint angles."""

    #: cable tension, N
    force_N: float
    #: channel voltages, V
    volts_V: Tuple[float, ...]
    #: the joint angles held, degrees
    joints_deg: Tuple[float, ...]
    #: the tensions that hold the posture (lo, hi), N; None when the tension was given
    range_N: Optional[Tuple[float, ...]]
    #: time from rest until every stack is within 1 % of its target thickness, s (None: past 600 s)
    settle_s: Optional[float]
    #: the reply set the board's targets (armed); False: nothing moved (disarmed). None from a
    #: firmware that does not say
    moved: Optional[bool]
    #: every field of the reply, parsed
    fields: Dict[str, Value] = field(default_factory=dict, compare=False)

    @classmethod
    def parse(cls, line: str) -> "Pose":
        f = parse_fields(line)
        settle = f.get("settle")
        moved = f.get("moved")
        return cls(
            force_N=_float(f["force"]),
            volts_V=_tuple(f["volts"]),
            joints_deg=_tuple(f["joints"]),
            range_N=_tuple(f["range"]) if "range" in f else None,
            settle_s=settle if isinstance(settle, float) else None,
            moved=None if moved is None else _float(moved) != 0.0,
            fields=f,
        )


class _Link:
    """Bytes out; lines in through a reader thread and a queue, so every read has a deadline.

    ``close`` ends the far side; the reader thread then sees the end of its input and stops,
    and only after it has stopped does ``release`` free what it reads from (a pipe's file
    descriptor): a descriptor freed under a reader that is still running can be reused by the
    next board's pipe, and the old reader would take that board's replies."""

    _CLOSED = object()

    def __init__(self, write, read_some, close, release=None):
        self._write = write
        self._close = close
        self._release = release
        self._lines: "queue.Queue[object]" = queue.Queue()
        self._thread = threading.Thread(target=self._pump, args=(read_some,), daemon=True)
        self._thread.start()

    def _pump(self, read_some) -> None:
        buf = b""
        try:
            while True:
                chunk = read_some()
                if chunk is None:  # end of the link
                    break
                buf += chunk
                while b"\n" in buf:
                    line, buf = buf.split(b"\n", 1)
                    self._lines.put(line.rstrip(b"\r").decode("ascii", "replace"))
        except Exception:  # the link broke: the reader reports it as closed
            pass
        self._lines.put(self._CLOSED)

    def send(self, data: bytes) -> None:
        try:
            self._write(data)
        except (OSError, serial.SerialException) as e:
            raise BoardLinkError(f"the board's link closed: {e}") from e

    def line(self, timeout_s: float, command: str) -> str:
        try:
            item = self._lines.get(timeout=timeout_s)
        except queue.Empty:
            raise BoardTimeout(command, timeout_s) from None
        if item is self._CLOSED:
            self._lines.put(item)
            raise BoardLinkError("the board's link closed")
        return str(item)

    def close(self) -> None:
        self._close()
        self._thread.join(timeout=10.0)
        if self._release is not None and not self._thread.is_alive():
            self._release()


def _serial_link(port: serial.SerialBase) -> _Link:
    def read_some():
        if not port.is_open:
            return None
        return port.read(max(1, port.in_waiting))  # returns b"" after the port's read time-out

    return _Link(port.write, read_some, port.close)


def _process_link(proc: subprocess.Popen, on_close=None) -> _Link:
    fd = proc.stdout.fileno()

    def write(data: bytes) -> None:
        proc.stdin.write(data)
        proc.stdin.flush()

    def read_some():
        data = os.read(fd, 4096)
        return data or None

    def close():
        try:
            proc.stdin.close()
        except OSError:
            pass
        if proc.poll() is None:
            proc.kill()
        proc.wait(timeout=10)

    def release():
        # the reader has stopped: its descriptor can go
        proc.stdout.close()
        if on_close:
            on_close()

    return _Link(write, read_some, close, release)


def _repo_roots() -> List[Path]:
    """The repository around the working directory and around this package (a venv inside it)."""
    roots = []
    for start in (Path.cwd(), Path(__file__).resolve()):
        for d in [start, *start.parents]:
            if (d / "tools" / "finger-sim" / "Cargo.toml").exists() and d not in roots:
                roots.append(d)
                break
    return roots


def _target_dirs(root: Path) -> List[Path]:
    env = os.environ.get("CARGO_TARGET_DIR")
    dirs = [Path(env) if Path(env).is_absolute() else root / env] if env else []
    return dirs + [root / "target"]


def find_sim() -> Path:
    """finger-sim: $SOFTFINGER_SIM, else a build in the repository's target directory (host
    triple or plain, debug or release), else `finger-sim` on PATH."""
    env = os.environ.get("SOFTFINGER_SIM")
    if env:
        return Path(env)
    for root in _repo_roots():
        for t in _target_dirs(root):
            cands = sorted(t.glob("*/debug/finger-sim")) + sorted(t.glob("*/release/finger-sim"))
            cands += [t / "debug" / "finger-sim", t / "release" / "finger-sim"]
            for c in cands:
                if c.is_file():
                    return c
    on_path = shutil.which("finger-sim")
    if on_path:
        return Path(on_path)
    raise BoardLinkError("finger-sim not found: build it (cargo build -p finger-sim --target host-tuple) or set SOFTFINGER_SIM")


def find_elf() -> Path:
    """The emulator firmware image: $SOFTFINGER_ELF, else the release image `cargo build
    --release` builds at the repository's top."""
    env = os.environ.get("SOFTFINGER_ELF")
    if env:
        return Path(env)
    for root in _repo_roots():
        for t in _target_dirs(root):
            p = t / "thumbv7em-none-eabihf" / "release" / "finger-fw"
            if p.is_file():
                return p
    raise BoardLinkError("no firmware image: build it with `cargo build --release` at the top, or set SOFTFINGER_ELF")


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Board:
    """A driver board's console.

    ``Board(port="/dev/ttyACM0")`` opens a real board (115200 8N1); :meth:`sim` starts the
    simulated board, :meth:`qemu` boots the emulator image. ``timeout_s`` bounds every reply.
    Use it as a context manager: ``stop`` is sent when the block ends, whatever ends it."""

    def __init__(self, port: Optional[str] = None, *, baudrate: int = 115200, timeout_s: float = 2.0, _link: Optional[_Link] = None):
        if _link is None:
            if port is None:
                raise BoardLinkError("name a board: Board(port=...), Board.sim() or Board.qemu()")
            try:
                ser = serial.serial_for_url(port, baudrate=baudrate, timeout=0.1)
            except (serial.SerialException, ValueError) as e:
                raise BoardLinkError(f"cannot open {port}: {e}") from e
            _link = _serial_link(ser)
        self._link = _link
        self.timeout_s = timeout_s
        self._closed = False
        #: the board's ``status`` 0.2 s (board time) after the ``stop`` that :meth:`close` sent,
        #: the HV modules' discharge of the stacks over (``vmeas_V`` ~0; None before, or when
        #: the board did not answer)
        self.final_status: Optional[Status] = None
        #: the lines before the last command's final reply (``help``'s list)
        self.before: List[str] = []
        #: final replies still to come for lines sent earlier (a command that timed out or was
        #: interrupted); the next command skips them
        self._late = 0

    # -- opening ---------------------------------------------------------------------------

    @classmethod
    def sim(cls, program: Union[str, Path, None] = None, *, timeout_s: float = 30.0) -> "Board":
        """finger-sim (the firmware's application on a simulated board) as a child process,
        over its stdin and stdout. Its time runs with the wall clock while it waits for the next
        line (a line takes none; :meth:`wait` runs its seconds of 1 ms control ticks at once), as
        a real board lives on between commands.
        ``timeout_s`` finds a board that hangs, not a slow one: a local child process on a
        loaded machine can wait seconds for the CPU.
        ``program``: default :func:`find_sim`."""
        prog = Path(program) if program else find_sim()
        try:
            proc = subprocess.Popen([str(prog)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, bufsize=0)
        except OSError as e:
            raise BoardLinkError(f"{prog}: {e}") from e
        return cls(timeout_s=timeout_s, _link=_process_link(proc))

    @classmethod
    def qemu(cls, elf: Union[str, Path, None] = None, *, timeout_s: float = 30.0, boot_timeout_s: float = 30.0,
             defmt_log: Union[str, Path, None] = None) -> "Board":
        """The firmware's emulator image booted in QEMU netduinoplus2 (deterministic ``-icount``),
        its console on a local TCP port opened with pyserial (``socket://``), its defmt log
        (semihosting) written to ``defmt_log`` (default: a temporary file). Waits for the boot
        banner. ``elf``: default :func:`find_elf`."""
        image = Path(elf) if elf else find_elf()
        if not image.is_file():
            raise BoardLinkError(f"{image}: no firmware image (build it with `cargo build --release` at the top)")
        scratch = tempfile.mkdtemp(prefix="softfinger-qemu-")
        log_path = Path(defmt_log) if defmt_log else Path(scratch) / "defmt.bin"
        last_err = "no attempt"
        for _ in range(3):  # a port taken between choosing and binding it: another port
            port = _free_port()
            log = open(log_path, "wb")
            try:
                proc = subprocess.Popen(
                    ["qemu-system-arm", "-machine", "netduinoplus2", "-cpu", "cortex-m4", "-display", "none", "-monitor", "none",
                     "-serial", f"tcp:127.0.0.1:{port},server=on,wait=on", "-icount", "shift=0,sleep=off",
                     "-semihosting-config", "enable=on,target=native", "-kernel", str(image)],
                    stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.PIPE)
            except OSError as e:
                log.close()
                shutil.rmtree(scratch, ignore_errors=True)
                raise BoardLinkError(f"qemu-system-arm: {e} (scripts/setup installs it)") from e
            log.close()
            t0 = time.monotonic()
            ser = None
            while ser is None and proc.poll() is None and time.monotonic() - t0 < boot_timeout_s:
                try:
                    ser = serial.serial_for_url(f"socket://127.0.0.1:{port}", timeout=0.1)
                except serial.SerialException:
                    time.sleep(0.02)
            if ser is None:
                if proc.poll() is None:
                    proc.kill()
                proc.wait()
                last_err = (proc.stderr.read() or b"").decode(errors="replace").strip() if proc.stderr else ""
                continue

            def close(ser=ser, proc=proc):
                ser.close()
                if proc.poll() is None:
                    proc.kill()
                proc.wait(timeout=10)
                if proc.stderr:
                    proc.stderr.close()
                shutil.rmtree(scratch, ignore_errors=True)

            link = _Link(ser.write, lambda ser=ser: ser.read(max(1, ser.in_waiting)) if ser.is_open else None, close)
            board = cls(timeout_s=timeout_s, _link=link)
            try:
                banner = link.line(boot_timeout_s, "(boot)")
            except (BoardTimeout, BoardLinkError):
                board.close(stop=False)
                raise
            if not banner.startswith("# "):
                board.close(stop=False)
                raise BoardLinkError(f"unexpected boot line from QEMU: {banner!r}")
            board.banner = banner
            return board
        shutil.rmtree(scratch, ignore_errors=True)
        raise BoardLinkError(f"QEMU's console did not open: {last_err}")

    # -- the console -----------------------------------------------------------------------

    def command(self, line: str, *, timeout_s: Optional[float] = None) -> str:
        """Send one command line; its final ``ok`` line (lines before it: :attr:`before`).
        Raises :class:`BoardError` on ``err``, :class:`BoardTimeout`, :class:`BoardLinkError`."""
        if self._closed:
            raise BoardLinkError("the board is closed")
        line = line.strip()
        if "\r" in line or "\n" in line:
            raise ValueError("one command per line")
        if not line:
            return ""
        t = self.timeout_s if timeout_s is None else timeout_s
        words = line.split()
        if words[0].lower() == "wait" and len(words) > 1:
            try:
                t += min(max(float(words[1]), 0.0), 3600.0) + WAIT_SLACK_S
            except ValueError:
                pass
        # Final replies come in the order of their lines, but for ``ok stopped``, which comes as
        # soon as the stop's line ends (docs/console.md "Lines"): the late replies of earlier
        # lines are skipped, and this line's reply is owed until it is read.
        earlier = self._late
        stop = words[0].lower() == "stop"
        self._link.send(f"{line}\r\n".encode("ascii"))
        self._late += 1
        before: List[str] = []
        while True:
            reply = self._link.line(t, line)
            final = _reply_final(reply)
            if final is None:
                before.append(reply)
                continue
            self._late -= 1
            if stop and reply == "ok stopped":
                self.before = before
                return reply
            if earlier > 0:
                earlier -= 1
                before = []
                continue
            if final[0] == "err":
                raise BoardError(final[1], final[2], line)
            self.before = before
            return reply

    def fields(self, line: str) -> Dict[str, Value]:
        """:meth:`command`, its reply's ``key=value`` fields parsed (numbers, tuples, text)."""
        return parse_fields(self.command(line))

    @staticmethod
    def _num(x: float) -> str:
        x = float(x)
        if x != x or x in (float("inf"), float("-inf")):
            raise ValueError(f"not a finite number: {x}")
        return repr(x)

    def version(self) -> str:
        """The firmware's ``version=`` field."""
        return str(self.fields("version")["version"])

    def status(self) -> Status:
        """Everything the board is doing (:class:`Status`)."""
        return Status.parse(self.command("status"))

    def limits(self) -> Limits:
        """The ceilings in force (:class:`Limits`)."""
        return Limits.parse(self.command("limits"))

    def solve(self, P: float, volts: Sequence[float]) -> BoardSolution:
        """The board's model at tension ``P`` (N) and channel voltages ``volts`` (V); nothing
        moves (:class:`BoardSolution`)."""
        return BoardSolution.parse(self.command("solve " + " ".join(self._num(x) for x in [P, *volts])))

    def arm(self) -> None:
        """Allow the HV outputs."""
        self.command("arm")

    def disarm(self) -> None:
        """Ramp the HV outputs to 0 and disable them."""
        self.command("disarm")

    def stop(self) -> None:
        """Emergency stop: HV to 0 at once, cable released, disarmed."""
        self.command("stop")

    def volt(self, ch: Union[int, str], V: float) -> Tuple[float, ...]:
        """Channel ``ch`` (1, 2, 3 or "all") target ``V`` volts (slewed; needs :meth:`arm`).
        Returns the channel targets, V."""
        if str(ch) not in ("1", "2", "3", "all"):
            raise ValueError(f"channel must be 1, 2, 3 or 'all', not {ch!r}")
        return _tuple(self.fields(f"volt {ch} {self._num(V)}")["volts"])

    def force(self, P: float) -> Force:
        """Cable tension target ``P`` (N); needs :meth:`arm` (:class:`Force`)."""
        return Force.parse(self.command(f"force {self._num(P)}"))

    def pose(self, d1: float, d2: float, d3: float, P: Optional[float] = None) -> Pose:
        """The inverse at the board: joint angles in degrees (and optionally the tension, N) to
        the force and voltages that hold them (:class:`Pose`; armed, the board moves there)."""
        args = [d1, d2, d3] + ([] if P is None else [P])
        return Pose.parse(self.command("pose " + " ".join(self._num(x) for x in args)))

    def param(self, name: Optional[str] = None, value: Optional[float] = None) -> Dict[str, Value]:
        """List every parameter (no name), read one, or set one (only while disarmed)."""
        if name is None:
            return self.fields("param")
        if value is None:
            return self.fields(f"param {name}")
        return self.fields(f"param {name} {self._num(value)}")

    def preset(self, name: str) -> None:
        """Every model parameter back to the model's defaults (``"default"``) or the paper's."""
        self.command(f"preset {name}")

    def wait(self, s: float) -> None:
        """Let ``s`` seconds pass on the board (its reply comes when they have)."""
        self.command(f"wait {self._num(s)}")

    # -- lifetime --------------------------------------------------------------------------

    def close(self, *, stop: bool = True) -> None:
        """Send ``stop`` (unless ``stop=False``; best effort) and close the link."""
        if self._closed:
            return
        if stop:
            self._safe_stop()
        self._closed = True
        self._link.close()

    def _safe_stop(self) -> None:
        """``stop`` (its ``ok stopped`` wherever it comes among the late replies of an
        interrupted command), then 0.2 s for the stacks to discharge (right after a stop they
        still hold their charge: ~0.1 s), then the board's ``status`` (:attr:`final_status`: HV
        at 0 and disarmed, as the board measures it), read past those late replies."""
        try:
            self.command("stop")
            self.command("wait 0.2")
            self.final_status = self.status()
        except (BoardTimeout, BoardLinkError, BoardError):
            return

    def __enter__(self) -> "Board":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        # also on KeyboardInterrupt (Ctrl-C), which reaches here like any exception
        self.close(stop=True)

    def __del__(self):
        try:
            if not self._closed:
                self._link.close()
        except Exception:
            pass
