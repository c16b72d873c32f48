"""Dask, imported when a distributed call needs it: `import particlemesh` (and the Blender
add-on) never needs Dask, and a missing Dask is one clear error."""


def distributed():
    """The `distributed` module (Dask's scheduler and client), or ImportError saying how to
    get it."""
    try:
        import distributed as module
    except ImportError as e:
        raise ImportError(
            "particlemesh.distributed needs Dask's distributed scheduler (Debian: apt install "
            "python3-distributed; elsewhere: pip install 'dask[distributed]'): " + str(e)) from e
    return module


def check_client(client):
    """A dask.distributed Client (anything with submit and gather), or TypeError."""
    if not (hasattr(client, "submit") and hasattr(client, "gather")):
        raise TypeError("client must be a dask.distributed.Client (e.g. Client(LocalCluster()) or "
                        f"Client('tcp://scheduler:8786')), not {type(client).__name__!r}")
    return client


def gather_in_order(futures, report=None):
    """The futures' results in their order, raising the first task's error (its own type and
    message); report(finished) as they end."""
    dd = distributed()
    out = [None] * len(futures)
    where = {f.key: i for i, f in enumerate(futures)}
    finished = 0
    for future in dd.as_completed(futures):
        out[where[future.key]] = future.result()
        finished += 1
        if report is not None:
            report(finished)
    return out
