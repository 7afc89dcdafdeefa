package naogateway.gateway.robot

import java.net.InetSocketAddress

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.proto.{Position, RobotHealth, Status}
import naogateway.wire.Posture
import naogateway.api.{LinkQuality, RobotSnapshot}

/** docs/protocol.md §6.2: what a keep-alive does to the published snapshot, and the restart rule. */
class KeepAliveSnapshotSpec extends AnyWordSpec with Matchers {

  private val start =
    RobotSnapshot(4, new InetSocketAddress("127.0.0.4", 3838), online = true, quality = LinkQuality.Good)

  // The simulated firmware's keep-alive: Status and RobotHealth, everything set.
  private val fullStatus = Status(
    timestamp = Some(600000L),
    teamID = Some(1),
    activeAgent = Some("soccer"),
    robotPosition = Some(Position(x = Some(-1200), y = Some(300), rotation = Some(0.5f))),
    activeRole = Some("striker"),
    currentState = Some("walking")
  )
  private val fullHealth =
    RobotHealth(batteryVoltage = Some(11.5f), posture = Some("walking"), uptimeMs = Some(600000), bootId = Some(3))

  // The thesis firmware's keep-alive after a power cycle: Status alone, team and agent only, a young clock.
  private val bareStatus = Status(timestamp = Some(400L), teamID = Some(1), activeAgent = Some("AgentTest"))

  // Keep-alives 200 ms apart by the gateway's clock, three in a row of a new session making a restart.
  private def run(steps: (Status, Option[RobotHealth])*): Vector[KeepAliveStep] =
    steps.foldLeft(Vector.empty[KeepAliveStep]) { (done, keepAlive) =>
      val (snapshot, sessions) = done.lastOption.fold((start, SessionRule.empty))(s => (s.snapshot, s.sessions))
      done :+ KeepAliveStep.keepAlive(snapshot, sessions, keepAlive._1, keepAlive._2,
        receivedAtNanos = 1000000000000L + done.size * 200000000L, keepAlives = 3)
    }

  "A keep-alive" should {
    "publish what it carries" in {
      val s = run(fullStatus -> Some(fullHealth)).last
      s.restarted shouldBe false
      s.snapshot shouldBe start.copy(
        teamId = Some(1),
        role = Some("striker"),
        agent = Some("soccer"),
        posture = Some(Posture.Walking),
        batteryVoltage = Some(11.5),
        uptimeMillis = Some(600000L),
        bootId = Some(3),
        position = Some((-1200, 300, 0.5)),
        receivedAtNanos = 1000000000000L
      )
    }

    "carry nothing over from the previous session when the new one sends Status only" in {
      val Vector(_, restart) = run(fullStatus -> Some(fullHealth), bareStatus -> None)
      // One keep-alive of a new session is no restart yet (the rule wants three in a row), but it is shown as it is.
      restart.restarted shouldBe false
      restart.snapshot shouldBe start.copy(teamId = Some(1), agent = Some("AgentTest"), uptimeMillis = Some(400L),
        receivedAtNanos = 1000200000000L)
      restart.snapshot.batteryVoltage shouldBe None
      restart.snapshot.position shouldBe None
      restart.snapshot.role shouldBe None
      restart.snapshot.posture shouldBe None
      restart.snapshot.bootId shouldBe None
    }

    "show a field as unknown when the robot stops sending it, without taking that for a restart" in {
      val later = fullStatus.copy(timestamp = Some(600200L), activeRole = None, robotPosition = None)
      val Vector(_, next) = run(fullStatus -> Some(fullHealth),
        later -> Some(fullHealth.copy(uptimeMs = Some(600200), batteryVoltage = None)))
      next.restarted shouldBe false
      next.snapshot.role shouldBe None
      next.snapshot.position shouldBe None
      next.snapshot.batteryVoltage shouldBe None
      next.snapshot.bootId shouldBe Some(3)
      next.sessions.current.flatMap(_.bootId) shouldBe Some(3)
    }
    "carry a posture this build does not know as the robot reported it, and take Status' posture without RobotHealth" in {
      val Vector(unknown, fromStatus) =
        run(fullStatus -> Some(fullHealth.copy(posture = Some("kneeling"))),
          fullStatus.copy(currentState = Some("fallen")) -> None)
      unknown.snapshot.posture.map(_.name) shouldBe Some("kneeling")
      unknown.snapshot.posture.get should not be a[Posture.Target]
      Posture.known.map(_.name) should not contain "kneeling"
      fromStatus.snapshot.posture shouldBe Some(Posture.Fallen)
    }

    "read back what the snapshot's report writes (one mapping both ways)" in {
      val s = run(fullStatus -> Some(fullHealth)).last.snapshot
      RobotSnapshot.afterKeepAlive(start, s.report.status, Some(s.report.health), s.receivedAtNanos) shouldBe s
      s.report.status shouldBe fullStatus.copy(timeOnline = Some(600))
      s.report.health shouldBe fullHealth
    }
  }

  "The restart rule" should {
    "see a new bootId, and a clock that went back, only from three keep-alives in a row of the new session" in {
      val steps = run(
        fullStatus -> Some(fullHealth),
        fullStatus.copy(timestamp = Some(600200L)) -> None, // RobotHealth left out: no bootId, the same clock
        fullStatus.copy(timestamp = Some(600400L)) -> Some(fullHealth.copy(uptimeMs = Some(600400))),
        fullStatus.copy(timestamp = Some(600600L)) -> Some(fullHealth.copy(uptimeMs = Some(600600),
            bootId = Some(4))), // odd
        fullStatus.copy(timestamp = Some(600800L)) -> Some(
          fullHealth.copy(uptimeMs = Some(600800))), // the session goes on
        bareStatus -> None, // a power cycle to Status-only firmware: the clock went back
        bareStatus.copy(timestamp = Some(600L)) -> None,
        bareStatus.copy(timestamp = Some(800L)) -> Some(RobotHealth(uptimeMs = Some(800), bootId = Some(1))),
        bareStatus.copy(timestamp = Some(1000L)) -> Some(RobotHealth(uptimeMs = Some(1000), bootId = Some(1)))
      )
      steps.map(_.restarted) shouldBe Vector(false, false, false, false, false, false, false, true, false)
      steps.map(_.sessions.current.flatMap(_.bootId)) shouldBe Vector(Some(3), Some(3), Some(3), Some(3), Some(3),
        Some(3), Some(3), Some(1), Some(1))
      steps(1).snapshot.bootId shouldBe None
    }
  }
}
