#!/usr/bin/env bash
# Runs sbt for this build: a system sbt when one is installed, otherwise the sbt launcher fetched
# once with Maven into the local Maven repository. Either way sbt resolves only from the local
# caches and Maven Central (project/repositories).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"

sbt_version="$(sed -n 's/^sbt\.version *= *//p' project/build.properties | tr -d '[:space:]')"
repo_opts=(
  "-Dsbt.repository.config=$here/project/repositories"
  "-Dsbt.override.build.repos=true"
)
batch_opts=()
if [ ! -t 0 ] || [ -n "${CI:-}" ]; then
  batch_opts=("-Dsbt.supershell=false" "-Dsbt.ci=true" "-Dsbt.server.forcestart=false")
fi
jvm_opts=(-Xss4m -Xms512m -Xmx3g -XX:+UseParallelGC "-Dfile.encoding=UTF-8")

if command -v sbt >/dev/null 2>&1 && [ -z "${NAOGATEWAY_BOOTSTRAP_SBT:-}" ]; then
  java_args=()
  for o in "${jvm_opts[@]}"; do java_args+=("-J$o"); done
  exec sbt "${repo_opts[@]}" "${batch_opts[@]}" "${java_args[@]}" "$@"
fi

m2="${MAVEN_REPO_LOCAL:-$HOME/.m2/repository}"
launcher="$m2/org/scala-sbt/sbt-launch/$sbt_version/sbt-launch-$sbt_version.jar"
if [ ! -f "$launcher" ]; then
  command -v mvn >/dev/null 2>&1 || { echo "./sbt: neither sbt nor mvn is installed; install a JDK and Maven" >&2; exit 1; }
  echo "./sbt: fetching the sbt $sbt_version launcher with Maven (first run only)" >&2
  # Maven's own default follows Java's user.home, which need not be $HOME: name the repository explicitly.
  mvn -q -B dependency:get -Dtransitive=false "-Dmaven.repo.local=$m2" "-Dartifact=org.scala-sbt:sbt-launch:$sbt_version" >&2
fi
[ -f "$launcher" ] || { echo "./sbt: the sbt launcher is still missing at $launcher" >&2; exit 1; }

exec java "${jvm_opts[@]}" "${repo_opts[@]}" "${batch_opts[@]}" -jar "$launcher" "$@"
