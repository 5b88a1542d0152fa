"""Command line: ``sketchforge [DOC]`` (the app), ``replay``, ``info``, ``render``, and
``batch`` and ``dataset`` (:mod:`sketchforge.batch`).

Errors a user can cause print one line on stderr and exit with status 2; no traceback.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from pathlib import Path

from sketchforge.atomic import check_target, refuse_input_as_output, same_file
from sketchforge.errors import SketchforgeError, printable, quote, shorten

SUBCOMMANDS = ("replay", "info", "render", "plugins", "batch", "dataset")
#: ``render --isophotes``: more lines than this are closer than a pixel apart at any size.
MAX_ISOPHOTES = 255


def _warn_plugin_problems() -> None:
    """A plugin that could not be loaded (a missing dependency, a broken hook) is one line on
    stderr naming it, never a traceback; the command goes on with the other plugins."""
    from sketchforge.plugins.manager import default_host

    for text in default_host().problems:
        print(f"sketchforge: warning: {printable(text)}", file=sys.stderr)
class _Parser(argparse.ArgumentParser):
    """argparse quotes a bad argument whole ("invalid int value: '777…'"): its one error line
    is cut like every other message (a subparser is made of the same class)."""

    def error(self, message):
        super().error(shorten(message, 500))


def whole_number(text: str) -> int:
    """An integer argument, also written as an integral float ("1e21"); anything else is
    refused in one bounded line."""
    t = text.strip()
    try:
        if len(t) > 40:
            raise ValueError
        if any(c in t for c in ".eE"):
            v = float(t)
            if not (v == v and abs(v) < float("inf") and v == int(v)):
                raise ValueError
            return int(v)
        return int(t)
    except (ValueError, OverflowError):
        raise argparse.ArgumentTypeError(f"expected a whole number, got {quote(text, 40)}") from None


def light_argument(text: str):
    """``--light x,y,z`` (or ``x,y``: in the drawing plane): a direction towards the light on
    the hemisphere facing the viewer (z >= 0), normalised; refused in one bounded line."""
    from sketchforge.document.layer import Light

    t = text.strip()
    try:
        if len(t) > 200:
            raise ValueError
        parts = [float(v) for v in t.split(",")]
    except ValueError:
        raise SketchforgeError(f"--light must be 2 or 3 numbers x,y[,z] separated by commas, got {quote(text, 40)}") from None
    try:
        return Light.from_vector(parts)
    except SketchforgeError as exc:
        raise SketchforgeError(f"--light {quote(text, 40)}: {exc}") from None


def cmd_replay(args) -> int:
    from sketchforge.document import fileformat as ff
    from sketchforge.document.provenance import check_available
    from sketchforge.plugins.manager import default_host

    # Everything a refusal depends on is checked before any work, so it is the only line printed.
    for out, what in ((args.export, "export"), (args.save, "save")):
        if out:
            refuse_input_as_output(out, [args.doc], what)
            check_target(out)
    if args.export and args.save and same_file(args.export, args.save):
        raise SketchforgeError("--export and --save name the same file; choose two files")
    if args.frame is not None:
        if not args.export:
            raise SketchforgeError("--frame needs --export OUT (the file to write the posed frame to)")
        if args.layer:
            raise SketchforgeError("--frame poses the assembled model; it cannot be combined with --layer")
        if args.frame < 0:
            raise SketchforgeError(f"--frame must be 0 or more, got {quote(args.frame, 40)}")
    host = default_host()
    if args.export:
        host.exporter_for(Path(args.export))  # an unknown format, before the replay
    data = ff.read_json(args.doc)
    light, journal = ff.validate_header(data, str(args.doc))
    if args.check and data.get("snapshot") is None:
        # Exit 0 with nothing said read as a pass; without a snapshot nothing was compared.
        raise SketchforgeError(
            f"{args.doc} has no snapshot: nothing to compare (--check compares the replay with the saved snapshot)"
        )
    check_available(data, host, str(args.doc))  # names every missing plugin at once

    def progress(i, n):
        if args.verbose:
            print(f"replayed {i}/{n}", file=sys.stderr)

    doc = ff.replay_journal(light, journal, str(args.doc), host=host, progress=progress)
    if args.check:
        snap = ff.document_from_dict(data, str(args.doc), host=host)
        diffs = ff.compare(snap, doc)
        if diffs:
            from sketchforge.document.provenance import version_notes

            # A solver of another version explains a difference better than "mesh differs".
            notes = version_notes(data, host)
            why = f" ({'; '.join(notes)})" if notes else ""
            raise SketchforgeError(f"{args.doc}: replay differs from the saved snapshot: " + "; ".join(diffs) + why)
        print("replay matches the snapshot", file=sys.stderr)
    if args.export:
        out = Path(args.export)
        if args.frame is not None:
            mesh = doc.host.pose(doc, args.frame)
            if mesh is None:
                raise SketchforgeError("--frame needs an animation plugin (sketchforge-animate) and none is installed")
            doc.host.export(out, mesh=mesh)  # atomic, one-line errors naming the plugin
            print(
                f"wrote {printable(out)} (frame {quote(args.frame, 40)}, {mesh.n_vertices} vertices, {mesh.n_faces} triangles)",
                file=sys.stderr,
            )
        else:
            if args.layer:
                summary = doc.host.export(out, mesh=doc.export_mesh(args.layer))
            else:
                summary = doc.host.export(out, doc=doc)
                # the parts the assembly had to leave free, and why (issue 34): said, never silent
                model = doc.assembled() if doc.host.has_assembler() else None
                for text in getattr(model, "warnings", ()):
                    print(f"sketchforge: warning: {printable(text)}", file=sys.stderr)
            print(f"wrote {printable(out)} ({summary})", file=sys.stderr)
    if args.save:
        ff.save(doc, args.save)
    return 0


def cmd_info(args) -> int:
    """Layers, light and journal of a document. A document whose plugins are missing is still
    described (from its snapshot, read without them), followed by what it needs."""
    from sketchforge.document import fileformat as ff
    from sketchforge.document.provenance import missing_plugins
    from sketchforge.plugins.manager import default_host

    host = default_host()
    data = ff.read_json(args.doc)
    _, journal = ff.validate_header(data, str(args.doc))
    missing = missing_plugins(data, host)
    if missing:
        from sketchforge.document.summary import read_snapshot

        layers, l = read_snapshot(data, str(args.doc))
    else:
        doc = ff.document_from_dict(data, str(args.doc), host=host)
        layers, l = doc.layers, doc.light
    count = "?" if layers is None else len(layers)
    print(f"{printable(args.doc)}: {count} layers, light ({l.x:.4f}, {l.y:.4f}, {l.z:.4g}; elevation "
          f"{l.elevation:.1f}°), {len(journal)} journal entries")
    if layers is None:
        print("  (no snapshot: its layers are made by replaying the journal, which needs the missing plugins)")
    for i, layer in enumerate(layers or ()):
        nv = layer.mesh.n_vertices if layer.mesh is not None else 0
        nf = layer.mesh.n_faces if layer.mesh is not None else 0
        # As the assembly sees it: an open stroke whose ends met has no junction (a free part).
        free = layer.closed or (layer.mesh is not None and len(layer.mesh.junction) == 0)
        kind = "closed" if free else "open"
        vis = "" if layer.visible else " (hidden)"
        print(f"  {i}: {printable(layer.id)} '{printable(layer.name)}'{vis} {kind}, {nv} vertices, {nf} triangles, "
              f"{len(layer.edits)} sculpt edits")
    if missing:
        print(f"{printable(args.doc)} needs plugins that are not installed:")
        for item in missing:
            print(f"  {printable(item)}")
    return 0


def cmd_plugins(args) -> int:
    """Every plugin with its version, what it registers and its problems (as Help > Plugins)."""
    from sketchforge.plugins.inventory import format_inventory, plugin_inventory, unattributed_problems
    from sketchforge.plugins.manager import default_host

    host = default_host()
    entries = plugin_inventory(host)
    for line in format_inventory(entries, unattributed_problems(host, entries)):
        print(printable(line))
    return 0


def shading_for(host, shader: str | None, model: str | None, cel: bool) -> dict:
    """``render_top``'s shading arguments for ``--shader``, ``--model`` or ``--cel``: a display
    shader by name, or a reflectance model's own R(n, l); one line listing the installed ones
    for an unknown name."""
    if model is not None:
        models = host.reflectance_models
        if model not in models:
            raise SketchforgeError(f"--model {quote(model, 40)}: no such reflectance model is installed "
                                   f"(installed: {', '.join(sorted(models))})")
        return {"model": models[model]}
    if shader is not None:
        shaders = host.shaders
        if shader not in shaders:
            raise SketchforgeError(f"--shader {quote(shader, 40)}: no such display shader is installed "
                                   f"(installed: {', '.join(sorted(shaders))}; or --model NAME for a reflectance model)")
        return {"shader": shaders[shader].shade}
    return {"cel": cel}


def cmd_render(args) -> int:
    from sketchforge.document import fileformat as ff
    from sketchforge.geometry.raster import render_top, write_png
    from sketchforge.plugins.manager import default_host

    if args.size < 16 or args.size > 8192:
        raise SketchforgeError(f"--size must be between 16 and 8192, got {args.size}")
    if not 0 <= args.isophotes <= MAX_ISOPHOTES:
        raise SketchforgeError(f"--isophotes must be between 0 and {MAX_ISOPHOTES}, got {args.isophotes}")
    light = None if args.light is None else light_argument(args.light)
    host = default_host()
    shading = shading_for(host, args.shader, args.model, args.cel)
    refuse_input_as_output(args.png, [args.doc], "PNG")
    check_target(args.png)
    doc = ff.load(args.doc, host)
    meshes = [l.mesh for l in doc.layers if l.visible and l.mesh is not None]
    if not meshes:
        raise SketchforgeError(f"{args.doc}: no visible layer with a mesh to render")
    # --light shades the picture only: the document (and its sculpt edits) keep their own.
    img = render_top(meshes, (light or doc.light).direction, size=args.size, isophotes=args.isophotes, **shading)
    write_png(args.png, img)
    print(f"wrote {printable(args.png)} ({img.shape[1]}x{img.shape[0]})", file=sys.stderr)
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="sketchforge", description="Sculpt 3D shapes by drawing.")
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("replay", help="recompute a document from its journal, headlessly")
    r.add_argument("doc", type=Path)
    r.add_argument("--export", help="write the result (.obj .ply .stl .glb .gltf; an animated document's .glb holds its animation)")
    r.add_argument("--layer", help="export this layer's own mesh instead of the assembled model")
    r.add_argument("--frame", type=whole_number,
                   help="export the model posed at this animation frame (24 fps; past the loop it wraps round)")
    r.add_argument("--check", action="store_true", help="compare the replay with the saved snapshot")
    r.add_argument("--save", help="save the replayed document (with a fresh snapshot)")
    r.add_argument("-v", "--verbose", action="store_true")
    r.set_defaults(func=cmd_replay)
    i = sub.add_parser("info", help="print layers and vertex counts (and the plugins a document needs that are missing)")
    i.add_argument("doc", type=Path)
    i.set_defaults(func=cmd_info)
    pl = sub.add_parser("plugins", help="list every plugin: version, what it registers, its problems")
    pl.set_defaults(func=cmd_plugins)
    d = sub.add_parser("render", help="render the top view of the shaded layers to PNG (no OpenGL)")
    d.add_argument("doc", type=Path)
    d.add_argument("--png", required=True)
    d.add_argument("--size", type=whole_number, default=512)
    d.add_argument("--isophotes", type=whole_number, default=0, help="draw K isophote lines")
    look = d.add_mutually_exclusive_group()
    look.add_argument("--cel", action="store_true", help="three-tone cel shading")
    look.add_argument("--shader", metavar="NAME", help="a display shader: lambert, cel or a plugin's (sketchforge plugins)")
    look.add_argument("--model", metavar="NAME",
                      help="shade with a reflectance model's own R(n, l): lambertian or a plugin's (sketchforge plugins)")
    d.add_argument("--light", metavar="X,Y[,Z]",
                   help="shade with this light instead of the document's: a direction towards it, z >= 0 "
                        "(0,0,1 straight overhead; write --light=-1,0,1 when x is negative)")
    d.set_defaults(func=cmd_render)
    from sketchforge.batch.cli import add_parsers

    add_parsers(sub, whole_number)
    return p


def build_app_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="sketchforge", description="Sculpt 3D shapes by drawing (desktop app).")
    p.add_argument("doc", nargs="?", type=Path, help="document to open")
    p.add_argument("--screenshot", metavar="OUT.png", help="render the window to a PNG and exit")
    p.add_argument("--mode", choices=["editing", "observation"], default="editing")
    return p


def _warning_note(caught) -> str:
    """The numeric warnings (RuntimeWarning: numpy's "overflow encountered in multiply") a
    failed command raised, folded into its error line: " (on the way: ...)", or "". Other
    warnings (a library's deprecations) say nothing about the user's input: dropped."""
    texts = list(dict.fromkeys(str(w.message).strip().splitlines()[0] for w in caught
                               if issubclass(w.category, RuntimeWarning) and str(w.message).strip()))
    if not texts:
        return ""
    more = f" and {len(texts) - 2} more" if len(texts) > 2 else ""
    return f" (on the way: {'; '.join(texts[:2])}{more})"


def _stdout_gone() -> int:
    """The reader of stdout went away (``info | head -1``): the rest of the output has nowhere
    to go, which is no error. Later writes (the interpreter's own flush at exit) go to
    /dev/null, so no BrokenPipeError traceback follows; the status is a SIGPIPE death's."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):
        pass
    return 141


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        if argv and argv[0] in SUBCOMMANDS:
            args = build_parser().parse_args(argv)
            if args.cmd != "plugins":  # which lists them itself, each under its plugin
                _warn_plugin_problems()
            # One line, always: a solver's numeric warnings (RuntimeWarning lines before the
            # error line) are collected; a failure folds them into its line, a success has
            # been checked for non-finite results by the core and drops them.
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                try:
                    rc = args.func(args)
                except SketchforgeError as exc:
                    print(f"sketchforge: error: {printable(shorten(str(exc) + _warning_note(caught)))}", file=sys.stderr)
                    return 2
            sys.stdout.flush()  # here, where a closed pipe is caught, not at exit
            return rc
        args = build_app_parser().parse_args(argv)
        if args.screenshot and args.doc is not None:
            refuse_input_as_output(args.screenshot, [args.doc], "screenshot")
        from sketchforge.qt.app import run_app

        return run_app(args.doc, screenshot=args.screenshot, mode=args.mode)
    except SketchforgeError as exc:
        print(f"sketchforge: error: {printable(shorten(str(exc)))}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        return _stdout_gone()
    except KeyboardInterrupt:
        print("sketchforge: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
