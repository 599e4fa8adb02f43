#!/usr/bin/env bash
# scripts/get-schemas.sh from a local copy of the official schemas (LODFORGE_SCHEMAS, or
# ../shared/data beside the clone): every file checked, the directory usable by xmllint and by the
# tests; a copy with one file changed is refused, naming it, and leaves nothing behind.
# Exit 77 (skipped) without such a copy. Usage: get_schemas_test.sh SOURCE_DIR
set -euo pipefail
source_dir=$1
mirror=${LODFORGE_SCHEMAS:-$source_dir/../shared/data}
if [ ! -f "$mirror/citygml2-schemas/citygml/profiles/base/2.0/CityGML.xsd" ] || [ ! -f "$mirror/cityjson2-schemas/cityjson.min.schema.json" ]; then
  echo "skipped: no copy of the schemas to fetch from (set LODFORGE_SCHEMAS to a directory holding citygml2-schemas/ and cityjson2-schemas/)"
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
out=$("$source_dir/scripts/get-schemas.sh" --from "$mirror" "$work/schemas")
echo "$out"
case $out in *"64 files checked"*) ;; *) echo "FAIL: not every file checked"; exit 1 ;; esac
# A CityGML 2.0 document validates through the catalog, with no network.
cat > "$work/one.gml" <<'XML'
<?xml version="1.0" encoding="UTF-8"?>
<core:CityModel xmlns:core="http://www.opengis.net/citygml/2.0" xmlns:bldg="http://www.opengis.net/citygml/building/2.0" xmlns:gml="http://www.opengis.net/gml">
  <core:cityObjectMember><bldg:Building gml:id="b1"><bldg:measuredHeight uom="m">10.0</bldg:measuredHeight></bldg:Building></core:cityObjectMember>
</core:CityModel>
XML
XML_CATALOG_FILES=$work/schemas/citygml2-schemas/catalog.xml xmllint --noout --nonet \
  --schema "$work/schemas/citygml2-schemas/citygml/profiles/base/2.0/CityGML.xsd" "$work/one.gml"
sed 's/measuredHeight/measuredHight/g' "$work/one.gml" > "$work/bad.gml"
if XML_CATALOG_FILES=$work/schemas/citygml2-schemas/catalog.xml xmllint --noout --nonet \
  --schema "$work/schemas/citygml2-schemas/citygml/profiles/base/2.0/CityGML.xsd" "$work/bad.gml" 2>/dev/null; then
  echo "FAIL: a misspelled element validates"; exit 1
fi
# A copy with one schema changed is refused, naming it; nothing is left in place of the target.
cp -r "$mirror/citygml2-schemas" "$mirror/cityjson2-schemas" "$work/"
echo " " >> "$work/citygml2-schemas/citygml/building/2.0/building.xsd"
if err=$("$source_dir/scripts/get-schemas.sh" --from "$work" "$work/again" 2>&1); then
  echo "FAIL: a changed schema was accepted"; exit 1
fi
case $err in *"'citygml2-schemas/citygml/building/2.0/building.xsd' is not the official file"*) ;; *) echo "FAIL: $err"; exit 1 ;; esac
if [ -e "$work/again" ] || ls -a "$work" | grep -q partial; then echo "FAIL: a half-fetched directory was left"; exit 1; fi
# A directory that is not one of its own is not replaced.
mkdir -p "$work/mine" && echo keep > "$work/mine/notes.txt"
if err=$("$source_dir/scripts/get-schemas.sh" --from "$mirror" "$work/mine" 2>&1); then echo "FAIL: a user's directory was replaced"; exit 1; fi
case $err in *"does not hold schemas fetched here"*) ;; *) echo "FAIL: $err"; exit 1 ;; esac
[ -f "$work/mine/notes.txt" ] || { echo "FAIL: a user's file is gone"; exit 1; }
# Fetching again over its own directory works.
"$source_dir/scripts/get-schemas.sh" --from "$mirror" "$work/schemas" > /dev/null
echo "ok"
