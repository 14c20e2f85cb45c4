#!/usr/bin/env python3
"""The header declares only Nimbus names: every type, enum constant, macro and function it
defines starts with Nimbus, nimbus_ or NIMBUS_, so it can sit beside any engine's own names."""
import re
import sys

path = sys.argv[1] if len(sys.argv) > 1 else "include/nimbus.h"
code = re.sub(r"/\*.*?\*/", "", open(path).read(), flags=re.S)
code = re.sub(r"^\s*#\s*include.*$", "", code, flags=re.M)
declared = set()
declared |= set(re.findall(r"#\s*define\s+([A-Za-z_]\w*)", code))
declared |= set(re.findall(r"\b(?:struct|enum)\s+([A-Za-z_]\w*)", code))
declared |= set(re.findall(r"typedef\s+[^;{}]*?\b([A-Za-z_]\w*)\s*;", code))
declared |= set(re.findall(r"\}\s*([A-Za-z_]\w*)\s*;", code))
declared |= set(re.findall(r"^\s*([A-Za-z_]\w*)\s*=\s*-?\d+", code, flags=re.M))
declared |= set(re.findall(r"\b([A-Za-z_]\w*)\s*\([^)]*\)\s*;", code))
allowed = re.compile(r"^(Nimbus|nimbus_|NIMBUS_)")
# The include guard's macro is NIMBUS_H, the C++ guard __cplusplus is the compiler's.
foreign = sorted(n for n in declared if not allowed.match(n) and n != "__cplusplus")
if foreign:
    print(f"{path} declares names outside Nimbus/nimbus_/NIMBUS_: {', '.join(foreign)}")
    sys.exit(1)
print(f"{path}: {len(declared)} names, all Nimbus/nimbus_/NIMBUS_")
