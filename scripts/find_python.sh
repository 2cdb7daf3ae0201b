#!/usr/bin/env bash
# Prints the first python3 that imports torch and h5py (Debian's python3-torch
# lives under /usr/bin/python3, which need not be the python3 first on PATH).
for candidate in /usr/bin/python3 python3; do
  if "$candidate" -c "import torch, h5py" >/dev/null 2>&1; then
    command -v "$candidate"
    exit 0
  fi
done
echo "no python3 that imports torch and h5py; install python3-torch python3-h5py" >&2
exit 1
