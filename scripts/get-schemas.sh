#!/usr/bin/env bash
# Fetches the official CityGML 2.0 schemas (with GML 3.1.1, XLink and xAL) and CityJSON 2.0
# schemas, which lodforge does not ship, into a directory the tests find through
# LODFORGE_SCHEMAS, so that they validate every output against them (without it they skip those
# checks, saying so):
#   scripts/get-schemas.sh [DIR]             # DIR: default ${XDG_CACHE_HOME:-~/.cache}/lodforge/schemas
#   scripts/get-schemas.sh --from MIRROR DIR # from a local copy holding citygml2-schemas/ and cityjson2-schemas/
#   LODFORGE_SCHEMAS=DIR scripts/test.sh
# Sources, pinned (the same files as ../shared/data): the OGC schema files as GitHub
# highsource/ogc-schemas keeps them unmodified (commit 18ce899), and CityJSON's own schemas (GitHub
# cityjson/specs, commit 877ee49, CC0). Every file is checked against its SHA-256 below; the
# directory appears complete or not at all (built beside it, moved in place at the end).
# Licences: OGC schemas (c) OGC, redistributable under the OGC notice; xAL (c) OASIS; W3C schemas
# W3C licence; CityJSON schemas CC0 1.0.
set -euo pipefail
mirror=""
if [ "${1:-}" = "--from" ]; then
  [ $# -ge 2 ] || { echo "usage: $0 [--from MIRROR] [DIR]" >&2; exit 2; }
  mirror=$2
  shift 2
fi
case "${1:-}" in -h|--help) sed -n '2,15p' "$0"; exit 0 ;; -*) echo "usage: $0 [--from MIRROR] [DIR]" >&2; exit 2 ;; esac
target=${1:-${XDG_CACHE_HOME:-${HOME:?set HOME, or give DIR}/.cache}/lodforge/schemas}
# Only a directory of schemas this script wrote (or nothing) is replaced.
if [ -e "$target" ] && [ ! -f "$target/citygml2-schemas/catalog.xml" ] && [ -n "$(ls -A "$target" 2>/dev/null)" ]; then
  echo "get-schemas: '$target' exists and does not hold schemas fetched here; give a new or empty directory" >&2
  exit 1
fi
ogc=https://raw.githubusercontent.com/highsource/ogc-schemas/18ce89928006eee08ed7e5a6ce6ea016436a444b
original=$ogc/schemas/src/main/resources-original
cityjson=https://raw.githubusercontent.com/cityjson/specs/877ee49e16c82a4bc7ab598926efcb9ba1075374/schemas

# SHA-256 and path of every file, under citygml2-schemas/ or cityjson2-schemas/.
manifest=$(cat <<'LIST'
656906a728b9aed5dbba7cde4c0d22ee19dbd7e6a4da9132a6370b484837cf74  citygml2-schemas/citygml/2.0/ReadMe.txt
f87fe8de043a835ca6dedef7d198ac53fbe0aa8d6496b4d230145c765f38f431  citygml2-schemas/citygml/2.0/cityGMLBase.xsd
e2e6dbf966010f7b65faf69a5c2a70ffc7ffb113f2964844a7de5d7b82cfba78  citygml2-schemas/citygml/ReadMe.txt
4199977b3c2775f7382cb49820a05d65270261fdbcf96ec40e196d1165d25eb3  citygml2-schemas/citygml/appearance/2.0/appearance.xsd
9fd548e0e20d1c47973f04ef40721cac82160e766ed2ee36bc5a4f2c5a656cb6  citygml2-schemas/citygml/bridge/2.0/bridge.xsd
906c8f7ed29ed6352b8d1372661a80de113794c938c4a0865ef2d7bdb38e7d15  citygml2-schemas/citygml/building/2.0/building.xsd
4acc55c502ede8d009b589a7f7a9a173d113730a903c36a744463e99e2ee253f  citygml2-schemas/citygml/cityfurniture/2.0/cityFurniture.xsd
abdbab7e0ce8b475c4b1f6e7086eecea8b6df6ca29daa0b0e90b3d55894e5936  citygml2-schemas/citygml/cityobjectgroup/2.0/cityObjectGroup.xsd
47b8bd89589ef221c3b97fe7a707cd867a14fa299010be8f27e99e0970c12d29  citygml2-schemas/citygml/generics/2.0/generics.xsd
f98bdec0bc3ab81cc89e1574ffa7e0244042a4bae409ac9a971bed09c3247d8d  citygml2-schemas/citygml/landuse/2.0/landUse.xsd
a511ec64ec364134fbcc2ebe0958c87289ac318490e6e539aa2b38fc4bcc6e68  citygml2-schemas/citygml/profiles/base/2.0/CityGML.xsd
9cafca7d53f9d0fd9f2991fcb6d1abd527dcb6bd8394c01c977834c5ce2343fc  citygml2-schemas/citygml/relief/2.0/relief.xsd
af9b0e17621afd64758926432ec52715ac8369acc9e0ac353650892cb555bf0f  citygml2-schemas/citygml/texturedsurface/2.0/texturedSurface.xsd
61623e4c11dc0dc914ba905cb797481d2bbd2e512ea35094a55b0f3527c52369  citygml2-schemas/citygml/transportation/2.0/transportation.xsd
e340351793ed8db7e980a89a632468ef41fa16ba2a57ea58535373d7db060dc9  citygml2-schemas/citygml/tunnel/2.0/tunnel.xsd
c9b3d43504399876d94d124c5f7af7f811c3259795ff69888a9d90aa619b2864  citygml2-schemas/citygml/vegetation/2.0/vegetation.xsd
150ffcbb3c822236741e9efb60612ce05f8d5db96b911ab2f808cbc493992b16  citygml2-schemas/citygml/waterbody/2.0/waterBody.xsd
fefd4afa1bbf528cfcd5ae8f2cc8c4e1937f5cd8718793fde5b5dd4d4a9c0ff5  citygml2-schemas/citygml/xAL/OASIS_COPYRIGHT_NOTICE.pdf
c180d378496dd41551c64e0cd4a66ea323855f6de85018e05ab8114dbfa562f5  citygml2-schemas/citygml/xAL/xAL.xsd
1ad3ab76ce16b5d272d3b2adad25144eef5c340dcf4709f360ecbc092dc9111e  citygml2-schemas/gml/3.1.1/base/basicTypes.xsd
31e238a7625bb6f08d3b7f2d8cadd3817e0ccb269279ce0d4134d5848ad824b3  citygml2-schemas/gml/3.1.1/base/coordinateOperations.xsd
5d194502380d66f6750c481f68ffbabefb4a8790dbebb4e3047135a871b29f83  citygml2-schemas/gml/3.1.1/base/coordinateReferenceSystems.xsd
ba5d4d351d1ecc275abaa88bc3f4e263526e869056ec8d11b6b4cfa6cf1eb5fd  citygml2-schemas/gml/3.1.1/base/coordinateSystems.xsd
68f46c8de0c0ccd9ccd02b0f490117edc2ca8d57c0609796173f2f4c658dabb3  citygml2-schemas/gml/3.1.1/base/coverage.xsd
5e0398809ebf1885b04f413df12569a7eddc7773975db1ad3e57329b844a8151  citygml2-schemas/gml/3.1.1/base/dataQuality.xsd
68b341e83a6b7132e1ee63f8fcffadc5125a2bdbdda2e7d1a5611d8162ae4649  citygml2-schemas/gml/3.1.1/base/datums.xsd
365b26485e119440901a25dd46886de12cfd2b0f27d8b465f1c506afa275d5a3  citygml2-schemas/gml/3.1.1/base/defaultStyle.xsd
0c031a4cf085a1e495a85762172a13c5221c25af23007b3328f95ecc63601b79  citygml2-schemas/gml/3.1.1/base/dictionary.xsd
6dcede87a2fec8d9daa1fcd605a5596481c528147990ca0856c33e60bee066f7  citygml2-schemas/gml/3.1.1/base/direction.xsd
a17d6b052cb75ed6b342f9d7526b642daf31b715e588bc3b72cb0068a18b6afe  citygml2-schemas/gml/3.1.1/base/dynamicFeature.xsd
36dd578e74bfc913e7b8f78e1003a98bbabaadb693ea7d577dcb7ae8b5d86806  citygml2-schemas/gml/3.1.1/base/feature.xsd
b438f20abb5697b87d68979c44021117a859bbb8f0bdf44488c68bfc8145ca2b  citygml2-schemas/gml/3.1.1/base/geometryAggregates.xsd
addfe8997866b9b19e06dcab4c36ec99a23cc352c9d66ca0c0dbac9b245d8421  citygml2-schemas/gml/3.1.1/base/geometryBasic0d1d.xsd
f70d60629adf0e6cb17a735c0aa1367d4073458822c4a89e1034cfffebd050a9  citygml2-schemas/gml/3.1.1/base/geometryBasic2d.xsd
2ce094104fa5bde175fe1246e2c2612ae16862bd730b16896e04146954f7cb3d  citygml2-schemas/gml/3.1.1/base/geometryComplexes.xsd
298d359d83610e0c0efd4ae14bdd3d38ab6167e08b065bfb72e66a209cac70fe  citygml2-schemas/gml/3.1.1/base/geometryPrimitives.xsd
b7fcaf63660b8f9505c383edaf7ed4aa25d0750129eeb3819e1654dd996ff755  citygml2-schemas/gml/3.1.1/base/gml.xsd
5853e7faf42272adeb8dea0c7739243fc5221228dd4ac2f16ea4eaf30ac67709  citygml2-schemas/gml/3.1.1/base/gmlBase.xsd
184a953eb4ee6bfe17c62e2a407446af602782d167916f1b7b2c0529f22114cd  citygml2-schemas/gml/3.1.1/base/grids.xsd
c53bf83033bf989baa6ca50d956a46f90b23862ae2463879b9051d779ecdfaec  citygml2-schemas/gml/3.1.1/base/measures.xsd
000a77173d4979e2cad9d696d173abad2d30c807e197f2cf05c45dc9e294187d  citygml2-schemas/gml/3.1.1/base/observation.xsd
d07424782a210b1719e3131a104a1f95dbd84ee789a9e8fed4f7d2a6c11c2b57  citygml2-schemas/gml/3.1.1/base/referenceSystems.xsd
208f43442ebcf91666885396d2cac5dc06cb8da880a30bf26902d56fe2acbfe3  citygml2-schemas/gml/3.1.1/base/temporal.xsd
a849439f6cf97b6f1ddc5ec6d0eace9d96d234cd6003277eab6787855b330e6e  citygml2-schemas/gml/3.1.1/base/temporalReferenceSystems.xsd
c507feed9f9393e616c887189a6ad4dfb227e0cb51d9410a2f80dce395266925  citygml2-schemas/gml/3.1.1/base/temporalTopology.xsd
08cbe50aa848765dfecda183106a91cc533e9615f46e0feebcc9d6d03d9ab23e  citygml2-schemas/gml/3.1.1/base/topology.xsd
d7044a7aac4f4ed239dc5d6075cb9d8ce3cbf821472fb9bc3ac0007037052055  citygml2-schemas/gml/3.1.1/base/units.xsd
3e2eb6a488ec4ed70089b9ec8edc0d830305dd5efc8c754b6dec57566332679d  citygml2-schemas/gml/3.1.1/base/valueObjects.xsd
906b2d7b3552f9a194b4ad84de90e5473702b8107bd293840cb37cb52c879514  citygml2-schemas/gml/3.1.1/gml_3_1_1-ReadMe.txt
71a6af850b0701b34c594ba749ed42ce621cf669b3cb0ec339ce9dd254314787  citygml2-schemas/gml/3.1.1/smil/smil20-language.xsd
3e5224ef365247c202680e64d8e7bba4882697bc38442bbb883a8dd12cb86315  citygml2-schemas/gml/3.1.1/smil/smil20.xsd
4f4ff6a0d61d7b9b7d4d50a1693ebb5532e0a5bcd63bcc00a1b18798d8a1d083  citygml2-schemas/w3c/1999/xlink.xsd
61960fb3131e38022caad5360e2f33a3382578ab3c80cd58bd74320ede61b20c  citygml2-schemas/w3c/2001/xml.xsd
665a8add9b039d66ff6fb7bbd250c4c6cbc6deb471f5c92ed3fd01343cee5414  citygml2-schemas/xlink/1.0.0/xlinks.xsd
ba71d57b2b66fac8cb2f0fdd8171b24e1aad5cefe8ba25b090859a0e1121b63f  citygml2-schemas/xlink/ReadMe.txt
69d5c01ce61cb7967c036ee9d2dfd9b5c2ae8c0c9622b66acc97cdf7c778f815  cityjson2-schemas/appearance.schema.json
74e128f4505429775fb97da4132a06e2fb3b88116332d7f6893529841fb3505e  cityjson2-schemas/cityjson.min.schema.json
f1cb4b5e5087fea7bc88e8330ea1f999c0d1ddc29839331d25e5fa248fd365de  cityjson2-schemas/cityjson.schema.json
7374a31db91c1ddb59d3021573932739eeb3c8c96f737c2c2f9ed1fc69e1dd0a  cityjson2-schemas/cityjsonfeature.min.schema.json
0578b9ac6b7edae7a69b5a94a5fddac840a4df49b4da9b3ce9b576aa7d229898  cityjson2-schemas/cityjsonfeature.schema.json
d8f5504a3246319aa083d87ba55cc763979c7bcd5f98c120d26c63463b6ee6ac  cityjson2-schemas/cityobjects.schema.json
9f81ce7fb367a0434427c1bb14858455d94201490d968b6e82a282403149f438  cityjson2-schemas/geomprimitives.schema.json
7af467f5e73b3ab418e7dffd26fa2ea8b0aefae20b9b625d018e794fb5ca10a5  cityjson2-schemas/geomtemplates.schema.json
2dd186ba48def3adb967ef4bbd5c65183a09d8929d5ed09753dd3739adb7144f  cityjson2-schemas/metadata.schema.json
LIST
)

# Where each file comes from on the web.
url_of() {
  case $1 in
    citygml2-schemas/citygml/*) echo "$original/ogc/${1#citygml2-schemas/}" ;;
    citygml2-schemas/gml/*) echo "$original/ogc/${1#citygml2-schemas/}" ;;
    citygml2-schemas/xlink/1.0.0/*) echo "$original/bp-ogc/06-080r2/${1#citygml2-schemas/}" ;;
    citygml2-schemas/xlink/*) echo "$original/ogc/${1#citygml2-schemas/}" ;;
    citygml2-schemas/w3c/*) echo "$ogc/demos/csw/2.0.2/schemas/${1#citygml2-schemas/}" ;;
    cityjson2-schemas/*) echo "$cityjson/${1#cityjson2-schemas/}" ;;
  esac
}

parent=$(dirname "$target")
mkdir -p "$parent"
staging=$(mktemp -d "$parent/.schemas.partial-XXXXXX")
chmod 755 "$staging"  # (mktemp's 0700 would keep a shared cache from other users)
trap 'rm -rf "$staging"' EXIT
count=0
while read -r sum path; do
  mkdir -p "$staging/$(dirname "$path")"
  if [ -n "$mirror" ]; then
    cp "$mirror/$path" "$staging/$path" 2>/dev/null || { echo "get-schemas: '$mirror/$path' is missing" >&2; exit 1; }
  else
    curl -fsSL --retry 2 -o "$staging/$path" "$(url_of "$path")" ||
      { echo "get-schemas: cannot download $(url_of "$path") (no internet? a proxy? or give a local copy: --from MIRROR)" >&2; exit 1; }
  fi
  echo "$sum  $staging/$path" | sha256sum -c --quiet - >/dev/null 2>&1 ||
    { echo "get-schemas: '$path' is not the official file (SHA-256 differs from $sum)" >&2; exit 1; }
  count=$((count + 1))
done <<< "$manifest"

# The XML catalog that sends xmllint to these copies instead of the web.
cat > "$staging/citygml2-schemas/catalog.xml" <<'XML'
<?xml version="1.0"?>
<!DOCTYPE catalog PUBLIC "-//OASIS//DTD Entity Resolution XML Catalog V1.0//EN" "http://www.oasis-open.org/committees/entity/release/1.0/catalog.dtd">
<!-- Offline XML catalog (written by lodforge's scripts/get-schemas.sh): the absolute schema URLs of CityGML 2.0 and GML 3.1.1 to the local copies. -->
<catalog xmlns="urn:oasis:names:tc:entity:xmlns:xml:catalog">
  <rewriteSystem systemIdStartString="http://schemas.opengis.net/" rewritePrefix="./"/>
  <rewriteURI uriStartString="http://schemas.opengis.net/" rewritePrefix="./"/>
  <system systemId="http://www.w3.org/1999/xlink.xsd" uri="w3c/1999/xlink.xsd"/>
  <uri name="http://www.w3.org/1999/xlink.xsd" uri="w3c/1999/xlink.xsd"/>
  <system systemId="http://www.w3.org/2001/xml.xsd" uri="w3c/2001/xml.xsd"/>
  <uri name="http://www.w3.org/2001/xml.xsd" uri="w3c/2001/xml.xsd"/>
  <system systemId="http://docs.oasis-open.org/election/external/xAL.xsd" uri="citygml/xAL/xAL.xsd"/>
  <uri name="http://docs.oasis-open.org/election/external/xAL.xsd" uri="citygml/xAL/xAL.xsd"/>
</catalog>
XML
rm -rf "$target"
mv "$staging" "$target"
trap - EXIT
echo "get-schemas: $count files checked, in $target; run the tests with LODFORGE_SCHEMAS=$target"
