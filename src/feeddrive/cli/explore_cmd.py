"""`feeddrive explore`: the explorer page on a local web server."""

from __future__ import annotations

import typer

from ._common import app, console, user_errors

DEFAULT_PORT = 8050


@app.command("explore")
@user_errors
def explore_command(
    port: int = typer.Option(DEFAULT_PORT, "--port", help="TCP port on 127.0.0.1 [port "
                             "number]; 0 picks a free one."),
    preset_name: str | None = typer.Option(None, "--preset", help="Named parameter set to "
                                           "start from (default wang2021)."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML) to "
                                           "start from."),
) -> None:
    """Start the explorer page: a drive's table speed, friction curves, stability band and
    loop poles, with knobs to move (drive, speeds, position, gains, friction scale, torque
    ripple, compensation) and a critical-speed search.  Serves on 127.0.0.1 only and prints
    the address; Ctrl-C stops it.  Needs the explore extra: pip install 'feeddrive[explore]'."""
    from ..parameters import ParameterError, dumps, load, preset

    if preset_name and params_file:
        raise ParameterError("--params", params_file, "give either --preset or --params, not both")
    if not 0 <= port <= 65535:
        raise ParameterError("--port", port, "expected 0 … 65535 (0: a free port)")
    initial: dict[str, str] = {"preset": preset_name or "wang2021"}
    if params_file:
        initial["params"] = dumps(load(params_file))  # `extends` resolved beside the file
    else:
        preset(initial["preset"])  # an unknown name is refused here, not on the page
    try:
        from ..explore import MissingDependency, make_server
    except ImportError as err:  # pragma: no cover  (the package itself is always there)
        raise ParameterError("explore", str(err), "the explorer could not be loaded") from None
    try:
        server = make_server(port, initial)
    except MissingDependency as err:
        raise ValueError(str(err)) from None
    except OSError as err:
        raise ParameterError("--port", port, f"cannot listen on 127.0.0.1 ({err.strerror}); "
                             "choose another port, or 0 for a free one") from None
    console.print(f"feeddrive explore: {server.url}  (Ctrl-C stops it)", markup=False,
                  highlight=False, soft_wrap=True)
    try:
        server.serve_forever(poll_interval=0.2)
    except KeyboardInterrupt:
        console.print("stopped", markup=False, highlight=False)
    finally:
        server.server_close()
