#!/usr/bin/env bash
# Makes a test PKI for DDS Security (OMG DDS Security 1.1, Cyclone's bundled plugins) in DIR:
#   identity_ca.pem, permissions_ca.pem     the two CAs (self-signed, EC P-256)
#   <node>.cert.pem, <node>.key.pem         one identity per node, signed by the identity CA
#   governance.p7s                          what the domain protects (signed by the permissions CA)
#   permissions.p7s                         one grant per node: the topics it may publish and read
# Nodes and their topics are the table below; `tachi-<node> --secure DIR` picks <node> by default.
# "mouse" is tachi-viewer --mouse: a viewer that may also publish strokes (the blade of seed 001);
# "monitor" reads everything and publishes only its own status (tachi status/echo, tests).
# "pipeline" is `tachi run --in-process`: every node in one process, the process the security boundary
# (as a ROS 2 enclave); it may do what sensor, voice, filter, sim and viewer may.
# The keys are unencrypted and every identity's key sits in DIR: this is a test PKI. On real hosts,
# copy each host only its own <node>.key.pem (docs/reliability.md).
# Usage: make_test_pki.sh DIR [--days N]
set -euo pipefail

usage() { echo "usage: $0 DIR [--days N]" >&2; exit 2; }
[ $# -ge 1 ] || usage
dir=$1; shift
days=3650
while [ $# -gt 0 ]; do
  case $1 in
    --days) [ $# -ge 2 ] || usage; days=$2; shift 2 ;;
    *) usage ;;
  esac
done
command -v openssl >/dev/null || { echo "$0: openssl not found (scripts/setup.sh installs it)" >&2; exit 1; }
mkdir -p "$dir"
cd "$dir"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# node: topics it publishes | topics it reads. Every node publishes its heartbeat (tachi/node/status).
declare -A publishes=(
  [sensor]="tachi/hand/raw"
  [voice]="tachi/voice/command"
  [filter]="tachi/hand/stroke"
  [sim]="tachi/cloth/topology tachi/cloth/topology_delta tachi/cloth/state tachi/cloth/cut tachi/scene/object"
  [viewer]=""
  [mouse]="tachi/hand/stroke"
  [monitor]=""
)
declare -A reads=(
  [sensor]=""
  [voice]=""
  [filter]="tachi/hand/raw tachi/voice/command tachi/cloth/state"
  [sim]="tachi/hand/stroke tachi/voice/command tachi/node/status"
  [viewer]="tachi/cloth/topology tachi/cloth/topology_delta tachi/cloth/state tachi/cloth/cut tachi/scene/object tachi/hand/stroke tachi/node/status"
  [mouse]="tachi/cloth/topology tachi/cloth/topology_delta tachi/cloth/state tachi/cloth/cut tachi/scene/object tachi/hand/stroke tachi/node/status"
  [monitor]="*"
)
union() { tr ' ' '\n' <<<"$*" | sed '/^$/d' | sort -u | tr '\n' ' '; }
publishes[pipeline]=$(union "${publishes[sensor]} ${publishes[voice]} ${publishes[filter]} ${publishes[sim]}")
reads[pipeline]=$(union "${reads[filter]} ${reads[sim]} ${reads[viewer]}")
nodes=(sensor voice filter sim viewer mouse monitor pipeline)

# A distinct organisation per PKI: two PKIs made by this script never trust each other.
org="tachi test PKI $(openssl rand -hex 4)"

make_ca() {  # name common-name
  openssl ecparam -name prime256v1 -genkey -noout -out "$1.key.pem"
  openssl req -x509 -new -key "$1.key.pem" -sha256 -days "$days" -subj "/O=$org/CN=$2" -out "$1.pem"
}
make_ca identity_ca "tachi identity CA"
make_ca permissions_ca "tachi permissions CA"

topics_xml() (  # space-separated topic names -> <topic> elements
  set -f  # "*" (monitor reads every topic) is a DDS topic expression, not a glob over this folder
  for t in $1; do printf '            <topic>%s</topic>\n' "$t"; done
)

# A day back, so a clock a little behind the signing host still accepts the grants.
now=$(date -u -d "-1 day" +%Y-%m-%dT%H:%M:%S)
until=$(date -u -d "+$days days" +%Y-%m-%dT%H:%M:%S)
# Every partition: a run's nodes use "tachi.run.<id>" (bus/run_partition.hpp), the bus tools "*" to read
# every run, and a rule without <partitions> would allow only the default one.
partitions_xml="
            <partitions><partition>*</partition></partitions>"
grants=""
for node in "${nodes[@]}"; do
  openssl ecparam -name prime256v1 -genkey -noout -out "$node.key.pem"
  openssl req -new -key "$node.key.pem" -subj "/O=$org/CN=$node" -out "$tmp/$node.csr"
  openssl x509 -req -in "$tmp/$node.csr" -CA identity_ca.pem -CAkey identity_ca.key.pem -CAcreateserial \
    -CAserial "$tmp/identity_ca.srl" -days "$days" -sha256 -out "$node.cert.pem" 2>/dev/null
  # The plugin compares the grant's subject with the certificate's in RFC 2253 order (CN first).
  subject=$(openssl x509 -in "$node.cert.pem" -noout -subject -nameopt RFC2253 | sed 's/^subject=//')
  subscribe=""
  [ -n "${reads[$node]}" ] && subscribe="
          <subscribe>
            <topics>
$(topics_xml "${reads[$node]}")
            </topics>$partitions_xml
          </subscribe>"
  grants+="
    <grant name=\"$node\">
      <subject_name>$subject</subject_name>
      <validity><not_before>$now</not_before><not_after>$until</not_after></validity>
      <allow_rule>
        <domains><id_range><min>0</min><max>230</max></id_range></domains>
        <publish>
          <topics>
$(topics_xml "${publishes[$node]} tachi/node/status")
          </topics>$partitions_xml
        </publish>$subscribe
      </allow_rule>
      <default>DENY</default>
    </grant>"
done

cat > "$tmp/permissions.xml" <<EOF
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>$grants
  </permissions>
</dds>
EOF

# Every domain (0-230: Cyclone's parser refuses a range up to 232): only authenticated participants
# join; discovery, liveliness and every topic's data are encrypted; reading and writing any topic needs a grant.
cat > "$tmp/governance.xml" <<EOF
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains><id_range><min>0</min><max>230</max></id_range></domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>NONE</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
EOF

for doc in governance permissions; do
  openssl smime -sign -text -in "$tmp/$doc.xml" -signer permissions_ca.pem -inkey permissions_ca.key.pem \
    -out "$doc.p7s"
done
# The CAs' keys sign nothing at run time: keep them out of the directory the nodes read.
mkdir -p ca-keys
mv identity_ca.key.pem permissions_ca.key.pem ca-keys/
chmod 600 ./*.key.pem ca-keys/*.key.pem
echo "$dir: identity and permissions CAs, governance, permissions and identities for ${nodes[*]}"
