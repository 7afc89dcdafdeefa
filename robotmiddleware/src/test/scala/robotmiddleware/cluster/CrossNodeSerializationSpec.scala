package robotmiddleware.cluster

import naogateway.wire.ActuatorGroup

import java.io.NotSerializableException
import java.net.{InetAddress, InetSocketAddress}

import scala.jdk.CollectionConverters._
import scala.reflect.runtime.{universe => ru}

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.actor.typed.ActorRef
import akka.serialization.{SerializationExtension, SerializerWithStringManifest}
import com.typesafe.config.ConfigFactory
import org.scalacheck.Gen
import org.scalacheck.rng.Seed
import org.scalatest.wordspec.AnyWordSpecLike
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.api.{
  CallResult,
  GameStateUpdated,
  GatewayEvent,
  LinkQuality,
  LinkQualityChanged,
  LinkStats,
  RobotFailure,
  RobotForgotten,
  RobotOffline,
  RobotOnline,
  RobotRestarted,
  RobotSnapshot,
  RobotStatusUpdated,
  ServoReading,
  ServoReadings,
  SigningState,
  VisionFrame
}
import naogateway.wire.gamecontroller.{GameControlData, GameControllerGenerators}
import naogateway.wire.{HaViMoGrid, HaViMoRegion, Posture, RpcValue}
import robotmiddleware._

/** Every message that crosses nodes survives the protobuf serializer unchanged, and nothing falls back to Java. */
class CrossNodeSerializationSpec
    extends ScalaTestWithActorTestKit(CrossNodeSerializationSpec.config)
    with AnyWordSpecLike
    with ScalaCheckPropertyChecks
    with LogCapturing {
  import CrossNodeSerializationSpec._

  private val serialization = SerializationExtension(system)
  private val probe = createTestProbe[Any]()
  private val all = samples(probe.ref)

  /** Public leaf classes of a sealed hierarchy, found in the compiled signatures so a new message cannot be missed. */
  private def publicLeaves(tpe: ru.Type): Set[Class[_]] = {
    val mirror = ru.runtimeMirror(getClass.getClassLoader)
    def walk(symbol: ru.ClassSymbol): Set[Class[_]] =
      if (symbol.isSealed)
        symbol.knownDirectSubclasses.filter(_.isClass).map(_.asClass).filterNot(_.isPrivate).flatMap(walk)
      else Set(mirror.runtimeClass(symbol))
    walk(tpe.typeSymbol.asClass)
  }

  "CrossNodeSerializer" must {
    "have a sample of every public message of each hierarchy bound to it" in {
      val hierarchies = Seq(
        ru.typeOf[RobotMiddleware.Command],
        ru.typeOf[Operation],
        ru.typeOf[RobotFailure],
        ru.typeOf[SessionMessage],
        ru.typeOf[GatewayEvent],
        ru.typeOf[VisionFrame],
        ru.typeOf[RpcValue]
      )
      val leaves = hierarchies.flatMap(publicLeaves)
      leaves.size should be > 30
      leaves.foreach(leaf => withClue(leaf.getName)(all.exists(leaf.isInstance) shouldBe true))
      def manifest(m: AnyRef): String =
        serialization.findSerializerFor(m).asInstanceOf[SerializerWithStringManifest].manifest(m)
      all.map(manifest).toSet shouldBe manifests
    }

    "be the serializer of every cross-node message, with Java serialization off" in {
      system.classicSystem.settings.AllowJavaSerialization shouldBe false
      all.foreach(m => withClue(m)(serialization.findSerializerFor(m) shouldBe a[CrossNodeSerializer]))
    }

    "round-trip every cross-node message to an equal one" in {
      all.foreach(m => withClue(m)(serializationTestKit.verifySerialization(m)))
    }

    "round-trip every valid GameController packet of both versions" in {
      forAll(GameControllerGenerators.control) { data =>
        serializationTestKit.verifySerialization(data)
        serializationTestKit.verifySerialization(GameStateUpdated(data))
      }
    }

    "deliver deserialized copies when every local message is serialized (serialize-messages = on)" in {
      all.foreach { m =>
        probe.ref ! m
        val delivered = probe.receiveMessage()
        withClue(m) {
          delivered shouldBe m
          m match {
            case p: Product if p.productArity > 0 => delivered.asInstanceOf[AnyRef] should not be theSameInstanceAs(m)
            case _                                => ()
          }
        }
      }
    }

    "refuse what it cannot carry with an error, not a wrong message" in {
      // Replies are named types: no library class (a bare Vector) is bound, so one cannot cross nodes at all.
      val bindings = system.settings.config.getConfig("akka.actor.serialization-bindings").root
      val ours = bindings.keySet.asScala.filter(c => bindings.get(c).unwrapped == "robot-middleware")
      ours.filter(_.startsWith("scala.")) shouldBe empty
      serialization.serialize(Vector(snapshot)).isFailure shouldBe true
      val serializer = serialization.findSerializerFor(AppEvent.SafetyCleared(1)).asInstanceOf[CrossNodeSerializer]
      a[NotSerializableException] should be thrownBy serializer.fromBinary(Array.emptyByteArray, "NoSuchMessage")
      // A node of another build may send a posture to go to or a group this build does not have.
      val dance = robotmiddleware.cluster.proto.Operation(
        robotmiddleware.cluster.proto.Operation.Kind.Posture(robotmiddleware.cluster.proto.Operation.Posture("dance")))
      the[NotSerializableException] thrownBy serializer.fromBinary(dance.toByteArray, "Operation") should have message
        "CrossNodeSerializer: corrupt [Operation]: unknown posture 'dance' (sit, stand, crouch)"
      val legs = robotmiddleware.cluster.proto.LeasePreempted(7, "legs", "referee")
      the[NotSerializableException] thrownBy serializer.fromBinary(legs.toByteArray,
        "LeasePreempted") should have message
        "CrossNodeSerializer: corrupt [LeasePreempted]: unknown actuator group 'legs' (walk, head, arms, speech)"
    }
  }
}

/** Samples of every cross-node message, shared with the cluster spec. */
object CrossNodeSerializationSpec {

  /** Every message sent to a local actor goes through serialization, as if it crossed nodes. */
  val config = ConfigFactory.parseString("akka.actor.serialize-messages = on")

  /** Every manifest of CrossNodeSerializer: the samples must use all of them. */
  val manifests: Set[String] = Set(
    "RegisterApp",
    "Execute",
    "Send",
    "SendResult",
    "Acquire",
    "Release",
    "ListRobots",
    "WatchStatus",
    "WatchVision",
    "WatchLinkStats",
    "WatchGame",
    "WatchEvents",
    "AppRegistered",
    "CallResult",
    "LeaseResult",
    "RobotSnapshots",
    "Operation",
    "RobotFailure",
    "SubscribeAppEvents",
    "Close",
    "LeasePreempted",
    "SafetyStop",
    "SafetyCleared",
    "RobotSnapshot",
    "LinkStats",
    "VisionRegions",
    "VisionGrid",
    "RobotOnline",
    "RobotOffline",
    "LinkQualityChanged",
    "RobotStatusUpdated",
    "RobotRestarted",
    "RobotForgotten",
    "GameStateUpdated",
    "GameControlData",
    "RpcValue"
  )

  val ipv4: InetSocketAddress = new InetSocketAddress(InetAddress.getByAddress(Array[Byte](127, 0, 0, 7)), 11011)
  val named: InetSocketAddress =
    new InetSocketAddress(InetAddress.getByAddress("robot7", Array[Byte](127, 0, 0, 7)), 11011)
  val ipv6: InetSocketAddress =
    new InetSocketAddress(InetAddress.getByAddress(Array.fill[Byte](15)(0) :+ 1.toByte), 3838)
  val unresolved: InetSocketAddress = InetSocketAddress.createUnresolved("robot7.local", 11011)

  val snapshot: RobotSnapshot = RobotSnapshot(
    robotId = 7,
    address = ipv4,
    teamId = Some(12),
    role = Some("striker"),
    agent = Some("ballfollower"),
    posture = Some(Posture.Stand),
    batteryVoltage = Some(11.7),
    uptimeMillis = Some(123456L),
    bootId = Some(3),
    position = Some((1200, -300, 1.57)),
    online = true,
    quality = LinkQuality.Good,
    receivedAtNanos = 987654321L
  )

  val rpcValues: Vector[RpcValue] = Vector(
    RpcValue.Text("ok"),
    RpcValue.Text(""),
    RpcValue.UInt(0xffffffffL),
    RpcValue.Number(-1.5f),
    RpcValue.Binary(Vector[Byte](0, 1, -1)),
    RpcValue.Flag(true),
    RpcValue.Items(Vector(RpcValue.Items(Vector.empty), RpcValue.Text("nested")))
  )

  val operations: Vector[Operation] = Vector(
    Operation.Walk(0.2, -0.1, 0.5),
    Operation.Stop(),
    Operation.Head(1.0, -0.3),
    Operation.Arms(0.1, 0.2, -0.3, -0.4),
    Operation.Posture(Posture.Stand),
    Operation.Say("hello"),
    Operation.RawCall("system", "echo", rpcValues)
  )

  val failures: Vector[RobotFailure] = Vector(
    RobotFailure.RobotOffline(7),
    RobotFailure.UnknownRobot(8),
    RobotFailure.LeaseNotHeld(7, ActuatorGroup.Walk, Some("teleop")),
    RobotFailure.LeaseNotHeld(7, ActuatorGroup.Head, None),
    RobotFailure.RuleGate("no sending while the game is playing"),
    RobotFailure.Timeout(7, "motion.posture", 5000L),
    RobotFailure.RobotError(7, "unknown method: motion.fly"),
    RobotFailure.SafetyHold(7, "battery low"),
    RobotFailure.Overloaded(7, "too many operations wait for the robot"),
    RobotFailure.Superseded(7, "motion.walk"),
    RobotFailure.Interrupted(7, "motion.head")
  )

  val regions: VisionFrame.Regions = VisionFrame.Regions(
    7,
    frame = 4242L,
    timestampMs = Some(1234L),
    regions = Vector(HaViMoRegion(1, 2, 300, 12345L, 6789L, 90, 10, 80, 20), HaViMoRegion(0, 0, 0, 0L, 0L, 0, 0, 0, 0))
  )

  val grid: VisionFrame.Grid = VisionFrame.Grid(7, 4243L, None, HaViMoGrid(Vector.tabulate(768)(i => (i * 37).toByte)))

  val linkStats: LinkStats =
    LinkStats(7, 100L, 90L, 12000L, 8000L, Some(3.5), 0.02, 4L, Map("garbage" -> 2L, "unknown-robot" -> 1L))

  /** A GameController packet from the codec's generators, fixed by its seed. */
  val gameData: GameControlData = GameControllerGenerators.control.pureApply(Gen.Parameters.default, Seed(530L))

  /** One or more samples of every message that crosses nodes, with actor refs pointing at `ref`. */
  def samples(ref: ActorRef[Any]): Vector[AnyRef] =
    Vector[AnyRef](
      RobotMiddleware.RegisterApp("teleop", 3, ref, ref),
      RobotMiddleware.Acquire(ref, 7, ActuatorGroup.Head, ref),
      RobotMiddleware.Acquire(ref, 7, Set[ActuatorGroup](ActuatorGroup.Walk, ActuatorGroup.Head, ActuatorGroup.Speech),
        ref),
      RobotMiddleware.Release(ref, 7, ActuatorGroup.Speech),
      RobotMiddleware.Send(ref, 7, Operation.Head(0.5, -0.1), ref),
      RobotMiddleware.Send(ref, 7, Operation.RawCall("speech", "say", Vector(RpcValue.Text("hi"))), ref),
      RobotMiddleware.ListRobots(ref),
      RobotMiddleware.WatchStatus(Some(7), ref),
      RobotMiddleware.WatchStatus(None, ref),
      RobotMiddleware.WatchVision(7, ref, grid = true),
      RobotMiddleware.WatchLinkStats(7, ref),
      RobotMiddleware.WatchGame(ref),
      RobotMiddleware.WatchEvents(ref),
      RobotMiddleware.AppRegistered("teleop"),
      CallResult(7, "motion.walk", Right(None)),
      CallResult(7, "system.echo", Right(Some(rpcValues.last))),
      RobotMiddleware.LeaseResult(7, ActuatorGroup.Walk, Right(())),
      RobotMiddleware.LeaseResult(7, ActuatorGroup.all.toSet, Right(())),
      RobotMiddleware.RobotList(Vector(snapshot, snapshot.copy(robotId = 8, address = ipv6))),
      RobotMiddleware.RobotList(Vector.empty),
      RobotMiddleware.SendResult(7, "motion.head", Right(())),
      RobotMiddleware.SendResult(7, "speech.say",
        Left(RobotFailure.LeaseNotHeld(7, ActuatorGroup.Speech, Some("referee")))),
      SessionMessage.SubscribeAppEvents(ref),
      SessionMessage.Close,
      AppEvent.LeasePreempted(7, ActuatorGroup.Walk, "referee"),
      AppEvent.SafetyStop(7, "battery low"),
      AppEvent.SafetyCleared(7),
      snapshot,
      snapshot.copy(address = named, quality = LinkQuality.Degraded),
      snapshot.copy(online = false, quality = LinkQuality.Offline, development = true,
        signing = SigningState.Unsigned),
      snapshot.copy(signing = SigningState.Signed),
      snapshot.copy(signing = SigningState.Awaited),
      snapshot.copy(
        posture = Some(Posture.reported("kneeling"))), // a posture this build does not know crosses as reported
      RobotSnapshot(9, unresolved),
      snapshot.copy(servos = Some(ServoReadings(
          Vector(ServoReading(1, Some(512), Some(-40), Some(12.1), Some(41)), ServoReading(2, silent = true),
            ServoReading(3, Some(0), Some(1023), Some(9.6), Some(70), error = 32)),
          Some(4L),
          987654000L
        ))),
      snapshot.copy(servos = Some(ServoReadings(Vector.empty, None, 1L))),
      linkStats,
      linkStats.copy(rttMillis = None, rejected = Map.empty),
      regions,
      regions.copy(timestampMs = None, regions = Vector.empty),
      grid,
      RobotOnline(7, ipv4),
      RobotOffline(7, "no keep-alive for 3 probes"),
      LinkQualityChanged(7, LinkQuality.Good),
      LinkQualityChanged(7, LinkQuality.Degraded),
      LinkQualityChanged(7, LinkQuality.Offline),
      RobotStatusUpdated(snapshot),
      RobotRestarted(7, Some(4), Vector("havimo.regions", "havimo.grid")),
      RobotRestarted(7, None, Vector.empty),
      RobotForgotten(7, "offline for 120 s"),
      GameStateUpdated(gameData),
      gameData
    ) ++
      operations.map(o => RobotMiddleware.Execute(ref, 7, o, ref)) ++
      operations ++
      failures.map(f => CallResult(7, "motion.walk", Left(f))) ++
      failures.map(f => RobotMiddleware.LeaseResult(7, ActuatorGroup.Walk, Left(f))) ++
      failures ++
      rpcValues
}
