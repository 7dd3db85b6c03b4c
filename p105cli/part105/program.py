"""A model's own motion program (its ``kinematic_control``), sampled for ``solve --program``.

Read through the command's one :class:`~p105cli.part105.model_file.ModelFile` (the one its
mechanism was read from): the configuration sequence or prescribed path by
:mod:`p105cli.part105.motion`, its pairs and its link named as :mod:`p105cli.part105.layout`
names them (the names of the mechanism).
"""

from __future__ import annotations

from .model_file import ModelFile

__all__ = ["ProgramError", "motion_program"]


class ProgramError(ValueError):
    """A motion program that cannot be run; the message names the file and the ``#id``."""


def motion_program(model, mech, count, step, source, note=None):
    """The model's motion program, sampled: ``("values", t, driven)`` for a configuration
    sequence (the actuated pairs, else every pair it values), ``("path", t, poses, link,
    frame, frame name)`` for a prescribed path (``frame``: the frame of ``link`` on the
    path, None for the link frame).

    ``model``: the ModelFile ``mech`` was read from (or a document, read with its own
    profile); ``count``/``step`` sample it (default: its nodes); ``source`` names the file in
    errors; ``note(message)`` receives remarks (several programs: the first one runs)."""
    from p105cli.motion.sampling import SamplingError

    try:
        return _program_of(ModelFile.of(model), mech, count, step, source, note or (lambda message: None))
    except SamplingError as err:
        raise ProgramError(f"{source}: {err}") from None


def _program_of(mf, mech, count, step, source, note):
    from p105cli.motion.configurations import sample_configurations
    from p105cli.motion.paths import PathError, sample_path
    from p105cli.motion.sampling import Plan

    programs = []
    if "kinematic_control" in mf.schema.entities:
        for c in mf.ids_of_type("kinematic_control"):
            v = mf.lenient().get(c, "contained_kinematic_programs", None)
            programs += [x["ref"] for x in (v if isinstance(v, list) else [v])
                         if isinstance(x, dict) and "ref" in x]
    if not programs:
        raise ProgramError(f"{source}: the model has no kinematic_control (motion program); "
                           "drive it with --values, --set, --sweep or --path")
    prog = programs[0]
    if len(programs) > 1:
        note(f"{source}: the model has {len(programs)} motion programs; running the first, #{prog}")
    plan = Plan(step=step, count=count, nodes=step is not None)
    types = mf.types(prog)
    if "interpolated_configuration_sequence" in types:
        from .motion import read_configuration_sequences
        seqs, kinds, _ = read_configuration_sequences(mf)
        seq = next(q for q in seqs if q.id == prog)
        t = plan.grid(seq.t_start, seq.t_end, [n.t for n in seq.nodes])
        sampled = sample_configurations(seq, t, kinds)
        names = [p.name for p in mech.pairs if p.actuated and p.name in sampled.values] \
            or [n for n in seq.pair_names if n in mech.pair_names]
        driven = {}
        for name in names:
            vals = sampled.values[name]
            if vals.shape[1] == 1:
                driven[name] = vals[:, 0]
            else:
                driven.update({(name, j): vals[:, j] for j in range(vals.shape[1])})
        return "values", t, driven
    from .motion import read_paths
    paths = [p for p in read_paths(mf).paths if p.holder_id == prog]
    if not paths:
        raise ProgramError(f"{source}: #{prog}: the motion program is a "
                           f"{'+'.join(sorted(mf.leaf_types(prog)))} that p105 cannot run "
                           "(it runs configuration sequences and prescribed paths with geometry)")
    path = paths[0]
    if path.link is None or path.link not in mech.link_names:
        raise ProgramError(f"{source}: #{path.id}: the path is tied to no link of mechanism {mech.name!r}")
    frame = None
    if path.frame is not None:
        frames = mech.link(path.link).frames
        frame = frames.get(path.frame)
        if frame is None:  # the frame is the link frame itself, or a pair frame of the link
            frame = next((v for k, v in frames.items() if k.startswith(path.frame)), None)
    t = plan.grid(path.t_start, path.t_end, path.breakpoints)
    try:
        poses = sample_path(path, t).T
    except PathError as err:
        raise ProgramError(f"{source}: #{path.id}: {err}") from None
    return "path", t, poses, path.link, frame, path.frame
