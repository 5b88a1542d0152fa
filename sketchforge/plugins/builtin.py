"""The core plugin: the document's commands, the mesh exporters, the Lambertian reflectance
model and the display shaders (Lambertian clay, three-tone cel).

Registered first by :func:`sketchforge.plugins.manager.make_plugin_manager`, through the same
``register`` call a third-party plugin gets.
"""

from __future__ import annotations

from sketchforge.plugins.hookspecs import hookimpl


@hookimpl
def sketchforge_commands():
    from sketchforge.document.commands import CORE_COMMANDS

    return list(CORE_COMMANDS)


@hookimpl
def sketchforge_exporters():
    from sketchforge import exporters as ex
    from sketchforge.plugins.registry import Exporter

    return [
        Exporter("obj", (".obj",), ex.write_obj, "Wavefront OBJ (text)"),
        Exporter("ply", (".ply",), ex.write_ply, "Stanford PLY (binary)"),
        Exporter("stl", (".stl",), ex.write_stl, "STL (binary)"),
        Exporter("gltf", (".glb", ".gltf"), ex.write_gltf, "glTF 2.0 (.glb binary or .gltf embedded)"),
    ]


@hookimpl
def sketchforge_reflectance_models():
    # Imported here: the reflectance module imports jax (~0.5 s), which only solvers need.
    from sketchforge.geometry.reflectance import LAMBERTIAN

    return [LAMBERTIAN]


@hookimpl
def sketchforge_shaders():
    from sketchforge.geometry.shaders import CEL_SHADER, LAMBERT_SHADER

    return [LAMBERT_SHADER, CEL_SHADER]
