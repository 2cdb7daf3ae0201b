"""flowplan from Python: plan with an exported planner at the speed of flowplan's native kernels.

    import torch, flowplan
    planner = flowplan.load_planner("pretrained/franka_reach_planner.pt")
    start = torch.cat([planner.ik(torch.tensor([0.5, -0.3, 0.2])), torch.zeros(7)])  # (14,) at rest
    goal = torch.cat([planner.ik(torch.tensor([0.5, 0.3, 0.2])), torch.zeros(7)])
    plans = planner.sample(start, goal, 16, spheres=torch.tensor([[0.5, 0.0, 0.2, 0.1]]))  # (16, 64, 14)

`load_planner` returns a `Planner` with the exported module's interface (docs/export.md: `sample`, `plan`,
`tcp`, `ik`, `clearance`, `cost`, `settings`, `state_dim`, ...). With the package's C++ part
(`flowplan._flowplan`, built with flowplan) it runs the file's weights with flowplan's native kernels; with
PyTorch alone it runs the file's own portable code. Either way every call runs without gradients and with
TorchScript's graph executor optimisations off, so the first plan costs about what the later ones do.
"""
import io
import warnings

import torch

try:
    from . import _flowplan
except ImportError as missing:  # PyTorch alone: the portable code of the files
    _flowplan = None
    _why_portable = f"flowplan's C++ module is not importable ({missing})"
else:
    _why_portable = ""

__all__ = ["Error", "Planner", "load_planner", "native_kernels"]

#: What flowplan raises for bad input (a file that is not a planner, a planner that cannot take the kernels);
#: a RuntimeError. The message names the file.
Error = _flowplan.Error if _flowplan is not None else RuntimeError


def native_kernels():
    """Whether flowplan's native kernels are loaded in this process (the package's C++ module imports)."""
    return _flowplan is not None


class Planner:
    """An exported flowplan planner: the TorchScript module's methods and attributes, each method called
    under `torch.no_grad()` with the graph executor's optimisations off.

    Attributes:
        module: the TorchScript module itself (torch.jit.ScriptModule), for calls of your own.
        native: whether it runs flowplan's native kernels.
        source: the file it was loaded from.
    """

    def __init__(self, module, native, source):
        self.module = module
        self.native = native
        self.source = source

    def __getattr__(self, name):
        value = getattr(self.module, name)
        if not callable(value) or isinstance(value, torch.nn.Module):
            return value

        def call(*args, **kwargs):
            with torch.no_grad(), torch.jit.optimized_execution(False):
                return value(*args, **kwargs)

        call.__name__ = name
        call.__doc__ = f"The exported planner's {name} (docs/export.md), without gradients."
        return call

    def __repr__(self):
        kernels = "native kernels" if self.native else "portable code"
        return (f"<flowplan.Planner {self.source}: {self.module.planner}, states ({self.module.horizon}, "
                f"{self.module.state_dim}), {kernels}>")


def load_planner(path, native=None):
    """Loads an exported planner file (`flowplan export`, or one of pretrained/).

    Args:
        path: the file.
        native: None (default): flowplan's native kernels when they are loaded, else the file's portable code,
            with a warning saying why; True: native kernels or an error; False: the file as written.

    Returns:
        a Planner.

    Raises:
        flowplan.Error: the file is not a flowplan planner, or native=True and the kernels cannot run it.
        FileNotFoundError: there is no such file.
    """
    path = str(path)
    with open(path, "rb"):  # FileNotFoundError naming the path, before anything else
        pass
    if native is not False:
        if _flowplan is None:
            if native:
                raise Error(f"{path}: native kernels asked for, but {_why_portable}")
            warnings.warn(f"{path}: planning with the file's portable code: {_why_portable}", stacklevel=2)
        else:
            try:
                module = torch.jit.load(io.BytesIO(_flowplan.native_planner(path)))
                return Planner(module, True, path)
            except Error as error:
                if native or "not a flowplan planner" in str(error) or "not a TorchScript module" in str(error):
                    raise
                warnings.warn(f"{path}: planning with the file's portable code: {error}", stacklevel=2)
    try:
        module = torch.jit.load(path)
    except RuntimeError as error:
        raise Error(f"{path}: not a TorchScript module: {str(error).splitlines()[0]}") from None
    if not hasattr(module, "format_version"):
        raise Error(f"{path}: not a flowplan planner (a TorchScript module without format_version)")
    return Planner(module, False, path)
