"""How the stepping kernels become machine code: numba's decorators and the registration of the
plain-Python functions compiled code calls (`jit`, the only module of the package that imports
numba at its top), getting a command's kernels ready with an honest notice when numba compiles
(`compiling`), and the kernels compiled at build time and shipped in the wheel (`prebuilt`).

Importing this package imports nothing: the closed-form path never touches numba.
"""
