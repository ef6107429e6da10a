"""The compiled kernel of the DNBS step, bit-identical to the numpy reference: ``dnbs.kernel: auto`` (the
default: where it builds, else numpy; choice.py) or ``c`` (it, or exit 2).

The numeric core (``pa10_dnbs/core``) stays numpy only and is the reference: the compiled bank
subclasses ``DNBSControllers`` and replaces only the arithmetic of ``answer`` and ``learn`` with one C
kernel (``dnbs_kernel.c``, built on first use by the machine's C compiler into a per-user cache).
Same inputs, same result bits (test/test_compiled_dnbs.py); about 7 us per step of a 7-joint arm (the PA10) instead
of about 49 us (scripts/bench_dnbs_step.py, docs/timing.md).
"""
