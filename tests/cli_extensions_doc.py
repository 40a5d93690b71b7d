#!/usr/bin/env python3
"""docs/gltf.md's extension table is the one `visbuf extensions --markdown` prints (gltf_extensions.cpp's table):
the page a user reads cannot drift from what the importer does. Usage: cli_extensions_doc.py VISBUF DOC."""
import subprocess
import sys

visbuf, doc = sys.argv[1], sys.argv[2]
printed = subprocess.run([visbuf, "extensions", "--markdown"], check=True, stdout=subprocess.PIPE,
                         text=True).stdout.strip().splitlines()
text = open(doc).read().splitlines()
begin = next(i for i, l in enumerate(text) if l.startswith("<!-- extensions table"))
end = next(i for i, l in enumerate(text) if l.startswith("<!-- end of extensions table"))
documented = text[begin + 1:end]
if documented != printed:
    missing = [l for l in printed if l not in documented]
    extra = [l for l in documented if l not in printed]
    print("docs/gltf.md's extension table differs from `visbuf extensions --markdown`:", file=sys.stderr)
    for l in missing:
        print("  missing: " + l, file=sys.stderr)
    for l in extra:
        print("  stale:   " + l, file=sys.stderr)
    print("regenerate it with: visbuf extensions --markdown", file=sys.stderr)
    sys.exit(1)
print("docs/gltf.md: %d extension rows, equal to the code's table" % (len(printed) - 2))
