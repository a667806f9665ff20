#!/bin/sh
# Add lps-calib to the desktop menu of the current user (no root needed).
#
#   ./install-desktop.sh              from an unpacked bundle: uses ./lps-gui next to this script
#   packaging/install-desktop.sh      from a source checkout: uses `lps-gui` found on PATH
#   install-desktop.sh /path/lps-gui  any other launcher
#
# Installs the icon in every size into the hicolor theme and the desktop entry
# into $XDG_DATA_HOME/applications (default ~/.local/share/applications).
set -eu

here=$(cd "$(dirname "$0")" && pwd)
data_home=${XDG_DATA_HOME:-$HOME/.local/share}

if [ $# -ge 1 ]; then
    exec_path=$1
elif [ -x "$here/lps-gui" ]; then
    exec_path="$here/lps-gui"
elif command -v lps-gui >/dev/null 2>&1; then
    exec_path=$(command -v lps-gui)
else
    echo "install-desktop.sh: lps-gui not found; pass its path as the first argument" >&2
    exit 2
fi

for candidate in "$here/_internal/resources" "$here/../resources"; do
    if [ -f "$candidate/lps-gui.svg" ]; then resources=$candidate; break; fi
done
if [ -z "${resources:-}" ]; then
    echo "install-desktop.sh: icon folder not found next to $here; run it from the bundle or the checkout" >&2
    exit 2
fi
if [ -f "$here/lps-gui.desktop" ]; then entry="$here/lps-gui.desktop"; else entry="$here/../packaging/lps-gui.desktop"; fi

for size in 16 24 32 48 64 128 256; do
    mkdir -p "$data_home/icons/hicolor/${size}x${size}/apps"
    cp "$resources/lps-gui-$size.png" "$data_home/icons/hicolor/${size}x${size}/apps/lps-gui.png"
done
mkdir -p "$data_home/icons/hicolor/scalable/apps" "$data_home/applications"
cp "$resources/lps-gui.svg" "$data_home/icons/hicolor/scalable/apps/lps-gui.svg"

# Exec and TryExec get the absolute launcher path (quoted: it may contain spaces).
sed -e "s|^Exec=lps-gui|Exec=\"$exec_path\"|" -e "s|^TryExec=lps-gui|TryExec=$exec_path|" \
    "$entry" > "$data_home/applications/lps-gui.desktop"
chmod 644 "$data_home/applications/lps-gui.desktop"

command -v update-desktop-database >/dev/null 2>&1 && update-desktop-database -q "$data_home/applications" || true
command -v gtk-update-icon-cache >/dev/null 2>&1 && gtk-update-icon-cache -q -t "$data_home/icons/hicolor" || true
echo "installed $data_home/applications/lps-gui.desktop (Exec=$exec_path)"
