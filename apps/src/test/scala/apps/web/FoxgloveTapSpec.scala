package apps.web

import java.net.InetSocketAddress
import java.util.concurrent.{ArrayBlockingQueue, ConcurrentLinkedQueue}
import java.util.concurrent.atomic.AtomicInteger

import scala.concurrent.Future
import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.actor.typed.ActorRef
import akka.stream.{KillSwitches, UniqueKillSwitch}
import akka.stream.scaladsl.{Keep, Sink}
import org.scalatest.concurrent.Eventually
import org.scalatest.wordspec.AnyWordSpecLike
import spray.json._

import naogateway.api._
import naogateway.api.recording.{Decision, GatewayTap, RecordingSchema, TapReaderStats, TapSubscription, Tapped}
import naogateway.proto.{RecordedDatagram, RecordedPort, Response}
import naogateway.wire.MessageContents
import naogateway.wire.gamecontroller.{GameControlData, GameState}
import robotmiddleware.RobotMiddleware

/** The feed as a reader of the gateway's tap, with a tap of the test's own: it subscribes only while a client is
  * connected, puts every decision of the tap on /gateway/decisions (the outbox's and the gate's; events and the budget
  * it has from the middleware and the figures), every datagram on /gateway/datagrams, and gives at most
  * MaxRobotChannels robots channels of their own.
  */
class FoxgloveTapSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing with Eventually {

  /** A tap whose publishing the test does by hand, counting subscriptions. */
  private final class TestTap extends GatewayTap {
    val subscribed = new AtomicInteger
    val open = new ConcurrentLinkedQueue[ArrayBlockingQueue[Tapped]]()
    def subscribe(reader: String, capacity: Int): TapSubscription = {
      subscribed.incrementAndGet()
      val queue = new ArrayBlockingQueue[Tapped](capacity)
      open.add(queue)
      new TapSubscription {
        def drainTo(into: java.util.Collection[_ >: Tapped], max: Int): Int = queue.drainTo(into, max)
        def stats: TapReaderStats = TapReaderStats(reader, 0, 0)
        def close(): Unit = { open.remove(queue); () }
      }
    }
    def readers: Vector[TapReaderStats] = Vector.empty
    def publish(t: Tapped): Unit = open.asScala.foreach(_.offer(t))
  }

  private final class View(t: GatewayTap) extends GatewayView {
    private def no[A]: Future[A] = Future.failed(new IllegalStateException("not in this test"))
    def addresses(): Future[GatewayAddresses] = no
    def robots(): Future[Vector[RobotSnapshot]] = no
    def links(): Future[RobotLinks] = no
    def stats(): Future[GatewayStats] = no
    def traffic(): Future[TrafficStats] = no
    def gameState(): Future[Option[GameControlData]] = no
    def gameSource(): Future[GameSource] = no
    override def tap(): Future[GatewayTap] = Future.successful(t)
  }

  private val robot = new InetSocketAddress("127.0.0.5", 3838)
  private val port = new InetSocketAddress("127.0.0.1", 11011)

  /** A feed on a test tap with one connection whose updates are collected in `got`, once the feed reads the tap. */
  private final case class Reading(tap: TestTap, feed: ActorRef[FoxgloveFeed.Command],
      got: ConcurrentLinkedQueue[FoxgloveFeed.Update], kill: UniqueKillSwitch)

  private def reading(): Reading = {
    val tap = new TestTap
    val feed = spawn(FoxgloveFeed(createTestProbe[RobotMiddleware.Command]().ref, new View(tap)))
    val connected = createTestProbe[FoxgloveFeed.Feed]()
    feed ! FoxgloveFeed.Connect(connected.ref)
    val got = new ConcurrentLinkedQueue[FoxgloveFeed.Update]()
    val kill = connected.receiveMessage().updates.viaMat(KillSwitches.single)(Keep.right).to(Sink.foreach(got.add))
      .run()
    eventually(timeout(10.seconds))(tap.open.size shouldBe 1)
    Reading(tap, feed, got, kill)
  }
  "The feed's reading of the gateway's tap" should {
    "subscribe only while a client is connected, and carry every decision and datagram of the tap" in {
      val tap = new TestTap
      val feed = spawn(FoxgloveFeed(createTestProbe[RobotMiddleware.Command]().ref, new View(tap)))
      val connected = createTestProbe[FoxgloveFeed.Feed]()
      feed ! FoxgloveFeed.Connect(connected.ref)
      val start = connected.receiveMessage()
      start.channels.map(_.topic) should contain allOf (RecordingSchema.Topics.Decisions,
        RecordingSchema.Topics.Datagrams)
      tap.subscribed.get shouldBe 0 // nothing is asked of the gateway before a client reads
      val got = new ConcurrentLinkedQueue[FoxgloveFeed.Update]()
      val (kill, _) =
        start.updates.viaMat(KillSwitches.single)(Keep.right).toMat(Sink.foreach(got.add))(Keep.both).run()
      eventually(timeout(10.seconds))(tap.open.size shouldBe 1)
      val playing = GameReading.Known(GameState.Playing)
      tap.publish(Tapped.Decided(System.nanoTime(), Decision.Gate(open = false, playing)))
      tap.publish(Tapped.Decided(System.nanoTime(), Decision.Gate(open = true, GameReading.Known(GameState.Finished))))
      tap.publish(Tapped.Decided(System.nanoTime(), Decision.Outgoing(1, Priority.Command, "sent", Array(1, 2))))
      tap.publish(Tapped.Decided(System.nanoTime(), Decision.Published(RobotOnline(1, robot))))
      tap.publish(Tapped.Decided(System.nanoTime(), Decision.Budget(1L, 2L, 3, Map.empty)))
      tap.publish(Tapped.Datagram(System.nanoTime(), RecordedPort.GAME_CONTROLLER, received = true, robot, port,
          Array(7, 8, 9), -1))
      def decisions = got.asScala.toVector.collect {
        case FoxgloveFeed.Published(c, _, b) if c.topic == RecordingSchema.Topics.Decisions =>
          new String(b, "UTF-8").parseJson.asJsObject.fields("decision").asInstanceOf[JsString].value
      }
      def datagrams = got.asScala.toVector.collect {
        case FoxgloveFeed.Published(c, _, b) if c.topic == RecordingSchema.Topics.Datagrams =>
          RecordedDatagram.parseFrom(b)
      }
      eventually(timeout(10.seconds)) {
        decisions shouldBe Vector("gate-closed", "gate-open", "send")
        datagrams.map(d => (d.port, d.payload.toByteArray.toVector, d.source)) shouldBe
          Vector((RecordedPort.GAME_CONTROLLER, Vector[Byte](7, 8, 9), "127.0.0.5:3838"))
      }
      kill.shutdown()
      eventually(timeout(10.seconds))(tap.open.size shouldBe 0) // the last client gone: off the tap
      testKit.stop(feed)
    }

    "read the tap slower while ticks find little, back at the fastest pace after a full tick, never outside the bounds" in {
      import FoxgloveFeed.{nextTapInterval, TapEntriesPerTick, TapIntervalMax, TapIntervalMin}
      // Nothing found: twice as slow each tick, up to the slowest pace and no further.
      val quiet = Iterator.iterate(TapIntervalMin)(nextTapInterval(_, 0)).take(10).toVector
      quiet.take(4) shouldBe Vector(TapIntervalMin, TapIntervalMin * 2, TapIntervalMin * 4, TapIntervalMax)
      quiet.last shouldBe TapIntervalMax
      // A full tick: entries wait at the tap, so the next tick comes at the fastest pace.
      nextTapInterval(TapIntervalMax, TapEntriesPerTick) shouldBe TapIntervalMin
      // Half a tick's worth or more: the pace holds.
      nextTapInterval(TapIntervalMin * 2, TapEntriesPerTick / 2) shouldBe TapIntervalMin * 2
      nextTapInterval(TapIntervalMin * 2, TapEntriesPerTick / 2 - 1) shouldBe TapIntervalMin * 4
    }

    "show a robot frame the gateway did not accept (a stranger's, in robot 3's name) on no robot channel" in {
      val Reading(tap, feed, got, kill) = reading()
      def frame(id: Int) = MessageContents(id, rpcResponse = Some(Response(callId = Some(id))))
      def bytes(id: Int) = MessageContents.encodeFrame(frame(id)).toOption.get
      // The stranger's: raw only, as the port's reader publishes a frame it did not accept.
      tap.publish(Tapped.Datagram(System.nanoTime(), RecordedPort.ROBOT_PORT, received = true, robot, port, bytes(3),
          3))
      // Robot 4's own, accepted: on its channel, after the stranger's.
      tap.publish(Tapped.Datagram(System.nanoTime(), RecordedPort.ROBOT_PORT, received = true, robot, port, bytes(4), 4,
          decoded = Some(frame(4))))
      def topics = got.asScala.toVector.collect { case FoxgloveFeed.Advertised(cs) => cs.map(_.topic) }.flatten
      def replies = got.asScala.toVector.collect {
        case FoxgloveFeed.Published(c, _, b) if c.topic == RecordingSchema.Topics.Decisions => new String(b, "UTF-8")
      }
      // Robot 4's channel is advertised before its message and reply decision reach the stream: wait for the reply.
      eventually(timeout(20.seconds)) {
        topics should contain(RecordingSchema.Topics.message(4))
        replies.count(_.contains("\"reply\"")) shouldBe 1
      }
      topics should not contain RecordingSchema.Topics.message(3)
      kill.shutdown()
      testKit.stop(feed)
    }

    "give at most MaxRobotChannels robots message channels, however many robot ids the tap carries" in {
      val Reading(tap, feed, got, kill) = reading()
      val ids = 1 to RecordingSchema.MaxRobotChannels + 20
      ids.foreach { id =>
        val contents = MessageContents(id, rpcResponse = Some(Response(callId = Some(id))))
        val frame = MessageContents.encodeFrame(contents).toOption.get
        tap.publish(Tapped.Datagram(System.nanoTime(), RecordedPort.ROBOT_PORT, received = true, robot, port, frame,
            id, decoded = Some(contents)))
      }
      def topics = got.asScala.toVector.collect { case FoxgloveFeed.Advertised(cs) => cs.map(_.topic) }.flatten
      def replies = got.asScala.toVector.collect {
        case FoxgloveFeed.Published(c, _, b) if c.topic == RecordingSchema.Topics.Decisions => new String(b, "UTF-8")
      }
      eventually(timeout(20.seconds)) {
        replies.count(_.contains("\"reply\"")) shouldBe ids.size // every reply is a decision, channels or not
        topics.filter(_.endsWith("/message")) shouldBe
          (1 to RecordingSchema.MaxRobotChannels).map(RecordingSchema.Topics.message)
      }
      kill.shutdown()
      testKit.stop(feed)
    }
  }
}
