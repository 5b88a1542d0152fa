"""What a document needs of its plugin host: the :class:`DocumentHost` protocol.

A :class:`~sketchforge.document.document.Document` is handed its host by whoever makes it (the
app, the CLI, a script, a test: ``Document(host)``); the document never builds one and imports
nothing from the plugin host (``sketchforge.plugins``), which in turn builds its registries of
the document's command classes. So the layers run one way: document below host. The host
sketchforge ships, :class:`sketchforge.plugins.manager.PluginHost`, satisfies this protocol; a
test may hand over anything else that does.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Protocol


class DocumentHost(Protocol):
    """The plugin host as the document uses it (commands, solvers, provenance)."""

    #: The command registry: ``from_dict(entry) -> Command``, ``get(name) -> class``,
    #: ``names()``.
    commands: Any

    @property
    def reflectance_models(self) -> Mapping[str, Any]:
        """{name: ReflectanceModel} (an edit names its model)."""

    def command_class(self, name: str) -> type:
        """The command class registered as ``name`` (raises UnknownCommandError)."""

    def solvers(self, kind: str) -> Mapping[str, Any]:
        """{name: solver value} of one kind ("inflate", "sculpt", "assemble")."""

    def solver(self, kind: str, name: str | None = None) -> Any:
        """The solver ``name`` of ``kind`` (None: the default); raises UnknownSolverError."""

    def default_solver_name(self, kind: str) -> str | None:
        """The solver a document that names none uses."""

    def solver_params(self, kind: str, solver: Any, params: Mapping | None) -> dict:
        """``solver``'s complete parameters (raises ParameterError naming the solver)."""

    def inflate(self, points, closed: bool, params: dict, holes: Sequence = (), solver: str | None = None) -> Any:
        """A layer's front ``Mesh``, checked (raises a SketchforgeError naming the inflater)."""

    def has_assembler(self) -> bool:
        """Whether any assembler is installed."""

    def assemble(self, layers: Sequence, params: dict | None = None, solver: str | None = None) -> Any:
        """One closed ``Mesh`` from the layers, back to front."""

    def provider_of(self, item: Any) -> str | None:
        """The plugin that registered ``item`` (a command class, a model, a solver)."""

    def provider_version(self, plugin: str | None) -> str | None:
        """The installed version of ``plugin``'s distribution."""

    def validate_plugin_data(self, plugin_data: Mapping, where: str) -> None:
        """Check a file's plugin data with the plugins' validators (raises DocumentFormatError)."""
