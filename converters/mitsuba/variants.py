"""Variant choice and LLVM set-up.

Mitsuba runs here in ``llvm_ad_rgb`` (vectorised, JIT-compiled) where libLLVM 19 is installed,
which the Makefile does (Debian 12's default libLLVM 15 aborts in it); otherwise in
``scalar_rgb``, with a message saying why. Dr.Jit reads ``DRJIT_LIBLLVM_PATH`` when it is first
imported, so this module sets it before importing drjit, and the package imports it first.
"""

from __future__ import annotations

import os
import sys

#: Where Debian's libllvm19 package puts the library llvm_ad_rgb needs.
LIBLLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
if "DRJIT_LIBLLVM_PATH" not in os.environ and os.path.exists(LIBLLVM):
    os.environ["DRJIT_LIBLLVM_PATH"] = LIBLLVM

import mitsuba as mi  # noqa: E402  (after DRJIT_LIBLLVM_PATH is set)

#: The variants rtlab registers its plugins in, when this Mitsuba build and machine run them.
VARIANTS = ("scalar_rgb", "llvm_ad_rgb")


class MitsubaVariantError(RuntimeError):
    """A Mitsuba variant this build or this machine cannot run: not a fault of any scene."""


def llvm_available() -> tuple[bool, str]:
    """Whether llvm_ad_rgb can run here, and if not, why."""
    if "llvm_ad_rgb" not in mi.variants():
        return False, "this Mitsuba build has no llvm_ad_rgb variant"
    path = os.environ.get("DRJIT_LIBLLVM_PATH", "")
    if not path or not os.path.exists(path):
        return False, (
            f"libLLVM 19 not found ({LIBLLVM}); Debian's default libLLVM 15 aborts in "
            "llvm_ad_rgb. Run 'make setup' (it installs libllvm19)"
        )
    return True, ""


_fallback_told = False


def default_variant() -> str:
    """llvm_ad_rgb where it works, else scalar_rgb (saying why, once)."""
    global _fallback_told
    ok, why = llvm_available()
    if ok:
        return "llvm_ad_rgb"
    if not _fallback_told:
        print(f"rtlab: Mitsuba falls back to scalar_rgb: {why}", file=sys.stderr)
        _fallback_told = True
    return "scalar_rgb"


def check_variant(variant: str) -> None:
    """Raise ``MitsubaVariantError`` for a variant this build or machine cannot run."""
    if variant not in mi.variants():
        known = ", ".join(mi.variants())
        raise MitsubaVariantError(f"Mitsuba variant {variant!r} is not in this build ({known})")
    if variant.startswith("llvm_"):
        ok, why = llvm_available()
        if not ok:
            raise MitsubaVariantError(f"Mitsuba variant {variant!r} cannot run here: {why}")
