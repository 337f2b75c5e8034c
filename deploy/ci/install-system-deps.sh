#!/usr/bin/env bash
# Install the system tools that tests/deploy runs, when they are missing:
#   systemd-analyze  (Debian package systemd)     checks deploy/systemd/gauged.service; systemd
#                                                 also brings libseccomp2, which the sandbox test uses
#   promtool         (Debian package prometheus)  checks and unit-tests deploy/prometheus/
#
# Idempotent: a tool already on PATH is left alone, and with nothing missing the script only says so.
# As root with apt-get it installs the missing packages (quiet, non-interactive, no recommends).
# Otherwise (a developer's laptop without root, or not Debian) it installs nothing and prints the
# command to run; tests/deploy then skips the tests that need the missing tool, naming it.
# Exit status: 0 unless an install that was attempted failed.
set -euo pipefail

# tool -> Debian package, in a fixed order
TOOLS=(systemd-analyze:systemd promtool:prometheus)

missing=()
for entry in "${TOOLS[@]}"; do
    tool=${entry%%:*} package=${entry#*:}
    if command -v "$tool" >/dev/null 2>&1; then
        echo "install-system-deps: $tool found at $(command -v "$tool")"
    else
        echo "install-system-deps: $tool missing (Debian package $package)"
        missing+=("$package")
    fi
done

if [ ${#missing[@]} -eq 0 ]; then
    echo "install-system-deps: nothing to install"
    exit 0
fi

if [ "$(id -u)" -ne 0 ] || ! command -v apt-get >/dev/null 2>&1; then
    echo "install-system-deps: not root or no apt-get; installing nothing. To install:"
    echo "    sudo apt-get install -y --no-install-recommends ${missing[*]}"
    echo "install-system-deps: until then the deploy tests that need these tools are skipped"
    exit 0
fi

export DEBIAN_FRONTEND=noninteractive
# Installing the prometheus package would start a Prometheus server; the tests need only promtool.
# Debian's policy-rc.d hook (exit 101 = "action forbidden") keeps the package's service from being
# started during the install; it is put in place only if the machine has none, and removed after.
policy=/usr/sbin/policy-rc.d
if [ ! -e "$policy" ]; then
    printf '#!/bin/sh\nexit 101\n' >"$policy"
    chmod 755 "$policy"
    trap 'rm -f "$policy"' EXIT
    echo "install-system-deps: services of the installed packages will not be started"
fi

start=$(date +%s)
echo "install-system-deps: apt-get update"
apt-get update -qq
echo "install-system-deps: apt-get install ${missing[*]}"
apt-get install -y -qq --no-install-recommends -o Dpkg::Use-Pty=0 "${missing[@]}" >/dev/null
echo "install-system-deps: installed ${missing[*]} in $(( $(date +%s) - start )) s"
for entry in "${TOOLS[@]}"; do
    tool=${entry%%:*}
    command -v "$tool" >/dev/null 2>&1 || { echo "install-system-deps: $tool still missing" >&2; exit 1; }
done
