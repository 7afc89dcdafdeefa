import sbtdynver.GitDescribeOutput

/** The version `./sbt publishLocal` publishes, from the git tags (sbt-dynver's describe output). */
object Publishing {

  /** The version before any release tag. */
  val FirstVersion = "0.1.0-SNAPSHOT"

  /** A clean checkout at tag `vX.Y.Z` is `X.Y.Z`; anything else (commits after it, uncommitted changes) is
    * `X.Y.(Z+1)-SNAPSHOT`, the same for every commit until the next tag, so a team's build can name it; no tag (or no
    * git) is [[FirstVersion]].
    */
  def version(describe: Option[GitDescribeOutput]): String = describe.filter(_.ref.isTag) match {
    case None                             => FirstVersion
    case Some(out) if out.isCleanAfterTag => out.ref.dropPrefix
    case Some(out)                        => nextSnapshot(out.ref.dropPrefix)
  }

  /** `1.2.0` → `1.2.1-SNAPSHOT`; a tag that is not three numbers gets `-SNAPSHOT` appended. */
  def nextSnapshot(released: String): String = released.split('.') match {
    case Array(major, minor, patch) if (major + minor + patch).forall(_.isDigit) =>
      s"$major.$minor.${patch.toInt + 1}-SNAPSHOT"
    case _ => s"$released-SNAPSHOT"
  }
}
