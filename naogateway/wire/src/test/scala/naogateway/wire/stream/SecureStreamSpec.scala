package naogateway.wire.stream

import scala.concurrent.duration._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import SecureStream._
import StreamTestKit._

/** The header rules, step by step, at window 1 and above. */
class SecureStreamSpec extends AnyWordSpec with Matchers {

  private val thesis = StreamSettings.thesis

  /** Hands every datagram to the other side at once, until both are quiet; returns the data segments' headers. */
  private def pump(
      a0: SecureStream,
      b0: SecureStream,
      first: Step,
      now: Long
  ): (SecureStream, SecureStream, Vector[String], Vector[(Int, Int)]) = {
    var a = a0
    var b = b0
    var toB = datagrams(first)
    var toA = Vector.empty[Array[Byte]]
    var deliveredAtB = Vector.empty[String]
    var dataHeadersFromA = Vector.empty[(Int, Int)]
    var rounds = 0
    while ((toA.nonEmpty || toB.nonEmpty) && rounds < 100000) {
      rounds += 1
      toB.foreach { d =>
        if (d.length > HeaderBytes) dataHeadersFromA :+= ((d(0) & 0xff, d(1) & 0xff))
        val step = b.receive(d, now)
        b = step.state
        deliveredAtB ++= delivered(step)
        toA ++= datagrams(step)
      }
      toB = Vector.empty
      toA.foreach { d =>
        val step = a.receive(d, now)
        a = step.state
        toB ++= datagrams(step)
      }
      toA = Vector.empty
    }
    (a, b, deliveredAtB, dataHeadersFromA)
  }

  private def offerAll(start: SecureStream, payloads: Seq[String], now: Long): Step =
    payloads.zipWithIndex.foldLeft(Step(start, Vector.empty)) { case (acc, (p, i)) =>
      val step = acc.state.offer(p, i.toLong, now)
      Step(step.state, acc.outputs ++ step.outputs)
    }

  "SecureStream at window 1 (the thesis protocol)" should {

    "start with sequence number 0 and ACK byte maxSeq, and hold the next segment until the first is acknowledged" in {
      val a = SecureStream.initial(thesis, 0L)
      a.lastAcknowledged shouldBe 20
      a.lastInOrder shouldBe 20
      val s1 = a.offer("one", 1L, 0L)
      transmits(s1) shouldBe Vector(Vector(0, 20) ++ bytes("one").map(_ & 0xff))
      s1.state.nextTimerAt shouldBe Some(ms(200))
      val s2 = s1.state.offer("two", 2L, ms(1))
      s2.outputs shouldBe empty
      s2.state.queued shouldBe 1
      s2.state.inFlight shouldBe 1
      val s3 = s2.state.receive(segment(20, 0), ms(10))
      acknowledged(s3) shouldBe Vector(1L)
      headers(s3) shouldBe Vector((1, 20))
      s3.state.inFlight shouldBe 1
      s3.state.queued shouldBe 0
    }

    "play the thesis scenario: crossing sends, a piggybacked ACK that is lost, recovery by timeouts" in {
      // A fixed 200 ms timeout on both sides keeps the order of the thesis's figure 14.
      val settings = thesis.copy(minRto = 200.millis)
      var a = SecureStream.initial(settings, 0L)
      var b = SecureStream.initial(settings, 0L)

      // Both send at once.
      val a1 = a.offer("a1", 1L, 0L); a = a1.state
      a = a.offer("a2", 2L, 0L).state
      val b1 = b.offer("b1", 11L, 0L); b = b1.state
      b = b.offer("b2", 12L, 0L).state
      headers(a1) shouldBe Vector((0, 20))
      headers(b1) shouldBe Vector((0, 20))

      // B has nothing it may send, so it answers A's segment with a pure ACK at once.
      val bGetsA0 = b.receive(datagrams(a1).head, ms(5)); b = bGetsA0.state
      delivered(bGetsA0) shouldBe Vector("a1")
      transmits(bGetsA0) shouldBe Vector(Vector(20, 0))

      // A's own pure ACK for B's segment is lost on the way.
      val aGetsB0 = a.receive(datagrams(b1).head, ms(5)); a = aGetsB0.state
      delivered(aGetsB0) shouldBe Vector("b1")
      transmits(aGetsB0) shouldBe Vector(Vector(20, 0))

      // B's ACK frees A's window: A's next segment piggybacks the ACK of B's segment, and is lost too.
      val aGetsAck = a.receive(datagrams(bGetsA0).head, ms(10)); a = aGetsAck.state
      acknowledged(aGetsAck) shouldBe Vector(1L)
      headers(aGetsAck) shouldBe Vector((1, 0))
      a.nextTimerAt shouldBe Some(ms(210))

      // B's timeout comes first: it resends its segment, which ACKs A's first one again.
      b.nextTimerAt shouldBe Some(ms(200))
      val bTimeout = b.tick(ms(200)); b = bTimeout.state
      transmits(bTimeout) shouldBe Vector(Vector(0, 0) ++ bytes("b1").map(_ & 0xff))
      b.stats.retransmissions shouldBe 1
      b.rtoNanos shouldBe ms(400)

      // A has seen it before: dropped, answered with a pure ACK, which now gets through.
      val aGetsDup = a.receive(datagrams(bTimeout).head, ms(205)); a = aGetsDup.state
      delivered(aGetsDup) shouldBe empty
      a.stats.duplicatesDropped shouldBe 1
      transmits(aGetsDup) shouldBe Vector(Vector(0, 0))

      // A's timeout: it resends its lost segment.
      a.nextTimerAt shouldBe Some(ms(210))
      val aTimeout = a.tick(ms(210)); a = aTimeout.state
      transmits(aTimeout) shouldBe Vector(Vector(1, 0) ++ bytes("a2").map(_ & 0xff))

      // The recovered ACK lets B send its second segment.
      val bGetsAck = b.receive(datagrams(aGetsDup).head, ms(210)); b = bGetsAck.state
      acknowledged(bGetsAck) shouldBe Vector(11L)
      headers(bGetsAck) shouldBe Vector((1, 0))

      val bGetsA1 = b.receive(datagrams(aTimeout).head, ms(215)); b = bGetsA1.state
      delivered(bGetsA1) shouldBe Vector("a2")
      transmits(bGetsA1) shouldBe Vector(Vector(0, 1))

      val aGetsB1 = a.receive(datagrams(bGetsAck).head, ms(215)); a = aGetsB1.state
      delivered(aGetsB1) shouldBe Vector("b2")
      transmits(aGetsB1) shouldBe Vector(Vector(0, 1))

      acknowledged(a.receive(datagrams(bGetsA1).head, ms(220))) shouldBe Vector(2L)
      acknowledged(b.receive(datagrams(aGetsB1).head, ms(220))) shouldBe Vector(12L)
    }

    "wrap the sequence numbers past maxSeq" in {
      val payloads = (0 until 45).map(i => s"p$i")
      val first = offerAll(SecureStream.initial(thesis, 0L), payloads, 0L)
      val (a, b, deliveredAtB, dataHeaders) = pump(first.state, SecureStream.initial(thesis, 0L), first, 0L)
      deliveredAtB shouldBe payloads
      dataHeaders.map(_._1) shouldBe (0 until 45).map(_ % 21)
      a.lastAcknowledged shouldBe 44 % 21
      b.lastInOrder shouldBe 44 % 21
      a.stats.acknowledged shouldBe 45
    }

    "deliver a duplicate once and answer both copies" in {
      val b = SecureStream.initial(thesis, 0L)
      val first = b.receive(segment(0, 20, "x"), 0L)
      delivered(first) shouldBe Vector("x")
      transmits(first) shouldBe Vector(Vector(20, 0))
      val second = first.state.receive(segment(0, 20, "x"), ms(1))
      delivered(second) shouldBe empty
      transmits(second) shouldBe Vector(Vector(20, 0))
      second.state.stats.duplicatesDropped shouldBe 1
      second.state.stats.delivered shouldBe 1
    }

    "ignore and count malformed and misbehaving datagrams without answering them" in {
      val b = SecureStream.initial(thesis, 0L)
      val after0 = b.receive(segment(0, 20, "x"), 0L).state
      val bad = Seq(
        Array.emptyByteArray,
        Array[Byte](0),
        Array.fill[Byte](1401)(0),
        segment(5, 20, "out of window"),
        segment(19, 20, "too old for window 1"),
        segment(1, 3, "ACK for something never sent"),
        segment(42, 20, "sequence number above the limit"),
        Array[Byte](0, 42, 1, 2), // an FU-Remote frame
        Array[Byte]('R', 'G', 'm', 'e') // a GameController packet
      )
      val end = bad.foldLeft(after0) { (state, d) =>
        val step = state.receive(d, ms(1))
        step.outputs shouldBe empty
        step.state
      }
      end.stats.ignored shouldBe bad.size
      end.lastInOrder shouldBe 0
      end.stats.delivered shouldBe 1
    }

    "take data whose ACK is stale but disregard the ACK" in {
      var a = SecureStream.initial(thesis, 0L)
      a = a.offer("mine", 1L, 0L).state
      a = a.receive(segment(20, 0), ms(1)).state
      a.lastAcknowledged shouldBe 0
      val step = a.receive(segment(0, 20, "theirs"), ms(2))
      delivered(step) shouldBe Vector("theirs")
      step.state.lastAcknowledged shouldBe 0
      step.state.stats.ignored shouldBe 0
    }

    "refuse empty and oversize payloads with typed errors, and accept the largest that fits" in {
      val a = SecureStream.initial(thesis, 0L)
      a.send(Array.emptyByteArray, 1L, None, 0L) shouldBe Left(SendRefused.EmptyPayload(1L))
      a.send(new Array[Byte](1399), 2L, None, 0L) shouldBe Left(SendRefused.PayloadTooLarge(2L, 1399, 1398))
      val ok = a.send(new Array[Byte](1398), 3L, None, 0L)
      ok.map(step => datagrams(step).map(_.length)) shouldBe Right(Vector(1400))
    }

    "refuse a send beyond the send queue limit and leave the state unchanged" in {
      var a = SecureStream.initial(thesis.copy(sendQueueLimit = 3), 0L)
      (1 to 4).foreach(i => a = a.offer(s"p$i", i.toLong, 0L).state)
      a.inFlight shouldBe 1
      a.queued shouldBe 3
      a.send(bytes("p5"), 5L, None, 0L) shouldBe Left(SendRefused.SendQueueFull(5L, 3))
      a.queued shouldBe 3
      val afterAck = a.receive(segment(20, 0), ms(1)).state
      afterAck.queued shouldBe 2
      afterAck.send(bytes("p5"), 5L, None, ms(1)).isRight shouldBe true
    }

    "copy the payload it is given, so the caller may reuse the array" in {
      val buffer = bytes("abc")
      val step = SecureStream.initial(thesis, 0L).send(buffer, 1L, None, 0L).toOption.get
      buffer(0) = 'z'
      val resent = step.state.tick(ms(200))
      transmits(resent).map(_.drop(2).map(_.toChar).mkString) shouldBe Vector("abc")
    }

    "send nothing at all while fresh and nothing happens (protocol.md 11.3)" in {
      val a = SecureStream.initial(thesis, 0L)
      a.nextTimerAt shouldBe None
      a.idleAckDue shouldBe false
      a.tick(ms(200)).outputs shouldBe empty
      a.tick(ms(604000)).outputs shouldBe empty
    }

    "repeat the ACK of received data once as an idle ACK, then fall silent, and not answer it (protocol.md 11.4)" in {
      val answered = SecureStream.initial(thesis, 0L).receive(segment(0, 20, "x"), 0L)
      transmits(answered) shouldBe Vector(Vector(20, 0))
      answered.state.nextTimerAt shouldBe Some(ms(200))
      answered.state.tick(ms(199)).outputs shouldBe empty
      val idle = answered.state.tick(ms(200))
      transmits(idle) shouldBe Vector(Vector(20, 0))
      idle.state.nextTimerAt shouldBe None
      idle.state.tick(ms(400)).outputs shouldBe empty
      idle.state.tick(ms(60000)).outputs shouldBe empty
      // A duplicate of the data (its ACK was lost after all) is answered and earns one more idle ACK.
      val again = idle.state.receive(segment(0, 20, "x"), ms(1000))
      transmits(again) shouldBe Vector(Vector(20, 0))
      transmits(again.state.tick(ms(1200))) shouldBe Vector(Vector(20, 0))
      // The peer does not answer an idle ACK.
      SecureStream.initial(thesis, 0L).receive(datagrams(idle).head, ms(201)).outputs shouldBe empty
    }

    "owe no idle ACK for pure ACKs, nor after a reset" in {
      val pure = SecureStream.initial(thesis, 0L).receive(segment(20, 20), 0L)
      pure.outputs shouldBe empty
      pure.state.nextTimerAt shouldBe None
      val answered = SecureStream.initial(thesis, 0L).receive(segment(0, 20, "x"), 0L).state
      val reset = answered.reset(ms(100))
      reset.outputs shouldBe empty
      reset.state.nextTimerAt shouldBe None
      reset.state.tick(ms(10000)).outputs shouldBe empty
    }

    "send the idle ACK only once its own data is acknowledged" in {
      val a = SecureStream.initial(thesis, 0L).offer("q", 1L, 0L).state
      val answered = a.receive(segment(0, 20, "x"), ms(10))
      answered.outputs.collect { case Transmit(d) => d.length } shouldBe Vector(2)
      // Seq 0 is in flight: the retransmission timer is what runs, no idle ACK before the ACK.
      answered.state.nextTimerAt shouldBe Some(ms(200))
      transmits(answered.state.tick(ms(200))).map(_.take(2)) shouldBe Vector(Vector(0, 0))
      val acked = answered.state.receive(segment(0, 0), ms(20))
      acked.state.inFlight shouldBe 0
      // Due 200 ms after the last datagram sent, the ACK at 10 ms.
      acked.state.nextTimerAt shouldBe Some(ms(210))
      transmits(acked.state.tick(ms(210))) shouldBe Vector(Vector(0, 0))
    }

    "not fast-retransmit on duplicate ACKs" in {
      var a = SecureStream.initial(thesis, 0L)
      a = a.offer("x", 1L, 0L).state
      val dup1 = a.receive(segment(20, 20), ms(1))
      val dup2 = dup1.state.receive(segment(20, 20), ms(2))
      val dup3 = dup2.state.receive(segment(20, 20), ms(3))
      (dup1.outputs ++ dup2.outputs ++ dup3.outputs) shouldBe empty
      dup3.state.stats.fastRetransmissions shouldBe 0
    }

    "expire a queued payload without using a sequence number" in {
      var a = SecureStream.initial(thesis, 0L)
      a = a.offer("p1", 1L, 0L).state
      a = a.offer("p2", 2L, 0L, deadline = Some(ms(30))).state
      a.nextTimerAt shouldBe Some(ms(30))
      val tick = a.tick(ms(30))
      expired(tick) shouldBe Vector(2L)
      tick.outputs.collect { case t: Transmit => t } shouldBe empty
      tick.state.queued shouldBe 0
      val acked = tick.state.receive(segment(20, 0), ms(40))
      acknowledged(acked) shouldBe Vector(1L)
      acked.outputs.collect { case t: Transmit => t } shouldBe empty
      headers(acked.state.offer("p3", 3L, ms(41))) shouldBe Vector((1, 20))
    }

    "announce an expired segment with a skip notice, which the peer honours" in {
      var a = SecureStream.initial(thesis, 0L)
      a = a.offer("x", 1L, 0L, deadline = Some(ms(50))).state
      a = a.offer("y", 2L, ms(10)).state
      a.nextTimerAt shouldBe Some(ms(50))
      val expiry = a.tick(ms(50))
      expired(expiry) shouldBe Vector(1L)
      transmits(expiry) shouldBe Vector(Vector(0, 20))
      expiry.state.settled shouldBe 0
      expiry.state.lastAcknowledged shouldBe 20

      val b = SecureStream.initial(thesis, 0L)
      val skip = b.receive(datagrams(expiry).head, ms(55))
      delivered(skip) shouldBe empty
      skip.state.stats.skipped shouldBe 1
      skip.state.lastInOrder shouldBe 0
      transmits(skip) shouldBe Vector(Vector(20, 0))

      val next = expiry.state.receive(datagrams(skip).head, ms(60))
      acknowledged(next) shouldBe empty
      headers(next) shouldBe Vector((1, 20))
      delivered(skip.state.receive(datagrams(next).head, ms(65))) shouldBe Vector("y")

      val stubborn = SecureStream.initial(thesis.copy(honourSkipNotices = false), 0L)
      val ignored = stubborn.receive(datagrams(expiry).head, ms(55))
      ignored.outputs shouldBe empty
      ignored.state.lastInOrder shouldBe 20
      ignored.state.stats.skipped shouldBe 0
    }

    "start afresh on reset and send unacknowledged payloads again from sequence number 0" in {
      var a = SecureStream.initial(thesis, 0L)
      a = a.offer("x", 1L, 0L).state
      a = a.receive(segment(20, 0), ms(1)).state
      a = a.offer("y", 2L, ms(2)).state
      a = a.offer("z", 3L, ms(2)).state
      a = a.receive(segment(0, 0, "in"), ms(3)).state
      a.lastInOrder shouldBe 0
      val reset = a.reset(ms(4))
      transmits(reset) shouldBe Vector(Vector(0, 20) ++ bytes("y").map(_ & 0xff))
      reset.state.queued shouldBe 1
      reset.state.lastInOrder shouldBe 20
      reset.state.lastAcknowledged shouldBe 20
    }
  }

  "SecureStream at window > 1 (selective repeat)" should {
    val sr4 = StreamSettings.selectiveRepeat(window = 4)

    "buffer out-of-order segments within the window and deliver them in order" in {
      val b = SecureStream.initial(sr4, 0L)
      val s1 = b.receive(segment(1, 41, "b"), 0L)
      delivered(s1) shouldBe empty
      transmits(s1) shouldBe Vector(Vector(41, 41))
      s1.state.buffered shouldBe 1
      val s2 = s1.state.receive(segment(2, 41, "c"), 0L)
      val beyond = s2.state.receive(segment(4, 41, "beyond the window"), 0L)
      beyond.outputs shouldBe empty
      beyond.state.stats.ignored shouldBe 1
      val s3 = beyond.state.receive(segment(0, 41, "a"), 0L)
      delivered(s3) shouldBe Vector("a", "b", "c")
      transmits(s3) shouldBe Vector(Vector(41, 2))
      val dup = s3.state.receive(segment(0, 41, "a"), 0L)
      delivered(dup) shouldBe empty
      transmits(dup) shouldBe Vector(Vector(41, 2))
      dup.state.stats.duplicatesDropped shouldBe 1
    }

    "keep up to W segments in flight, fast-retransmit the oldest once, and resend at once on a partial ACK" in {
      var a = SecureStream.initial(sr4, 0L)
      val sent = (0 until 5).map { i =>
        val step = a.offer(s"p$i", i.toLong, 0L)
        a = step.state
        headers(step)
      }
      sent.flatten shouldBe Vector((0, 41), (1, 41), (2, 41), (3, 41))
      a.inFlight shouldBe 4
      a.queued shouldBe 1

      val dup1 = a.receive(segment(41, 41), ms(10))
      dup1.outputs shouldBe empty
      val dup2 = dup1.state.receive(segment(41, 41), ms(11))
      headers(dup2) shouldBe Vector((0, 41))
      dup2.state.stats.fastRetransmissions shouldBe 1
      val dup3 = dup2.state.receive(segment(41, 41), ms(12))
      dup3.outputs shouldBe empty

      val partial = dup3.state.receive(segment(41, 1), ms(20))
      acknowledged(partial) shouldBe Vector(0L, 1L)
      headers(partial) shouldBe Vector((2, 41), (4, 41))
      partial.state.stats.retransmissions shouldBe 2

      val full = partial.state.receive(segment(41, 3), ms(30))
      acknowledged(full) shouldBe Vector(2L, 3L)
      full.outputs.collect { case t: Transmit => t } shouldBe empty
      full.state.inFlight shouldBe 1
    }

    "resend a lost resend at once when more duplicate ACKs arrive than the segments ahead of it can explain" in {
      var a = SecureStream.initial(sr4, 0L)
      (0 until 8).foreach(i => a = a.offer(s"p$i", i.toLong, 0L).state)
      // Seq 0 and 2 are lost; the duplicate ACKs of 1 and 3 resend 0, whose arrival makes B acknowledge 1.
      val fast = a.receive(segment(41, 41), ms(10)).state.receive(segment(41, 41), ms(11))
      headers(fast) shouldBe Vector((0, 41))
      val partial = fast.state.receive(segment(41, 1), ms(20))
      headers(partial) shouldBe Vector((2, 41), (4, 41), (5, 41))
      // The resent seq 2 is lost too. Seq 3 went before the resent 0, so B answered it with an older ACK: nothing
      // was ahead of the resent 2, and the duplicate ACKs of 4 and 5 prove it lost.
      val dup4 = partial.state.receive(segment(41, 1), ms(30))
      dup4.outputs shouldBe empty
      val dup5 = dup4.state.receive(segment(41, 1), ms(31))
      headers(dup5) shouldBe Vector((2, 41))
      dup5.state.stats.lostRetransmissions shouldBe 1
      dup5.state.stats.timeouts shouldBe 0
      dup5.state.nextTimerAt shouldBe Some(ms(31) + dup5.state.rtoNanos)
    }

    "not resend the oldest again while the segments ahead of its resend can explain the duplicate ACKs" in {
      var a = SecureStream.initial(sr4, 0L)
      (0 until 4).foreach(i => a = a.offer(s"p$i", i.toLong, 0L).state)
      var step = a.receive(segment(41, 41), ms(10)).state.receive(segment(41, 41), ms(11))
      headers(step) shouldBe Vector((0, 41))
      // Seq 1 to 3 were ahead of the resend: each may still cause a duplicate ACK, and one more may be a duplicated
      // datagram, so four prove nothing; a fifth does.
      (1 to 4).foreach { i =>
        step = step.state.receive(segment(41, 41), ms(11L + i))
        step.outputs shouldBe empty
      }
      val fifth = step.state.receive(segment(41, 41), ms(16))
      headers(fifth) shouldBe Vector((0, 41))
      fifth.state.stats.lostRetransmissions shouldBe 1
    }

    "count no lost resends at window 1, where duplicate ACKs start nothing" in {
      var a = SecureStream.initial(thesis, 0L)
      a = a.offer("p0", 0L, 0L).state
      val timeout = a.tick(ms(200))
      headers(timeout) shouldBe Vector((0, 20))
      val dups = (1 to 5).foldLeft(timeout) { (st, i) => st.state.receive(segment(20, 20), ms(200L + i)) }
      dups.outputs shouldBe empty
      dups.state.stats.lostRetransmissions shouldBe 0
    }

    "on timeout resend only the oldest unacknowledged segment and back off" in {
      var a = SecureStream.initial(sr4, 0L)
      (0 until 4).foreach(i => a = a.offer(s"p$i", i.toLong, 0L).state)
      val timeout = a.tick(ms(200))
      headers(timeout) shouldBe Vector((0, 41))
      timeout.state.rtoNanos shouldBe ms(400)
      timeout.state.nextTimerAt shouldBe Some(ms(600))
    }

    "honour a skip notice only for the next expected number, then deliver the buffered successors" in {
      val b = SecureStream.initial(sr4, 0L)
      val buffered = b.receive(segment(1, 41, "b"), 0L).state.receive(segment(3, 41, "d"), 0L).state
      // Byte 0 of an ordinary pure ACK can lag a whole window behind, so numbers further ahead prove nothing.
      val ahead = buffered.receive(segment(1, 41), ms(1))
      ahead.outputs shouldBe empty
      ahead.state.lastInOrder shouldBe 41
      val skip = ahead.state.receive(segment(0, 41), ms(1))
      delivered(skip) shouldBe Vector("b")
      skip.state.stats.skipped shouldBe 1
      skip.state.lastInOrder shouldBe 1
      transmits(skip) shouldBe Vector(Vector(41, 1))
      val skipMore = skip.state.receive(segment(2, 41), ms(2))
      delivered(skipMore) shouldBe Vector("d")
      skipMore.state.lastInOrder shouldBe 3
      skipMore.state.stats.skipped shouldBe 2

      val stubborn = SecureStream.initial(sr4.copy(honourSkipNotices = false), 0L)
      val held = stubborn.receive(segment(1, 41, "b"), 0L).state.receive(segment(0, 41), ms(1))
      held.outputs shouldBe empty
      held.state.lastInOrder shouldBe 41
    }

    "announce several expired segments one at a time, each once the previous one is skipped" in {
      var a = SecureStream.initial(sr4, 0L)
      a = a.offer("p0", 0L, 0L, deadline = Some(ms(50))).state
      a = a.offer("p1", 1L, 0L, deadline = Some(ms(50))).state
      val p2 = a.offer("p2", 2L, 0L)
      a = p2.state
      var b = SecureStream.initial(sr4, 0L).receive(datagrams(p2).head, ms(5)).state
      b.buffered shouldBe 1

      val expiry = a.tick(ms(50))
      expired(expiry) shouldBe Vector(0L, 1L)
      transmits(expiry) shouldBe Vector(Vector(0, 41))
      expiry.state.settled shouldBe 1

      val skip0 = b.receive(datagrams(expiry).head, ms(55)); b = skip0.state
      transmits(skip0) shouldBe Vector(Vector(41, 0))
      val next = expiry.state.receive(datagrams(skip0).head, ms(60))
      acknowledged(next) shouldBe empty
      transmits(next) shouldBe Vector(Vector(1, 41))

      val skip1 = b.receive(datagrams(next).head, ms(65)); b = skip1.state
      delivered(skip1) shouldBe Vector("p2")
      b.stats.skipped shouldBe 2
      val done = next.state.receive(datagrams(skip1).head, ms(70))
      acknowledged(done) shouldBe Vector(2L)
      done.state.inFlight shouldBe 0
    }

    "not reuse a sequence number while a recent retransmission of its previous user may still be on its way" in {
      // Window 4 over 8 numbers: a receiver holding segment 4 takes the numbers 5, 6, 7 and 0 as new, and 0 is also
      // the number of segment 0. So segment 4 waits until the retransmitted segment 0 can no longer arrive: minRto
      // (20 ms, as there is no round-trip sample yet) after it was sent again.
      val tight = StreamSettings(window = 4, maxSeq = 7)
      var a = SecureStream.initial(tight, 0L)
      (0 until 8).foreach(i => a = a.offer(s"p$i", i.toLong, 0L).state)
      a = a.receive(segment(7, 7), ms(10)).state.receive(segment(7, 7), ms(11)).state
      a.stats.retransmissions shouldBe 1
      val acked = a.receive(segment(7, 3), ms(13))
      acknowledged(acked) shouldBe Vector(0L, 1L, 2L, 3L)
      headers(acked) shouldBe empty
      acked.state.nextTimerAt shouldBe Some(ms(31))
      acked.state.tick(ms(30)).outputs shouldBe empty
      val later = acked.state.tick(ms(31))
      headers(later) shouldBe Vector((4, 7), (5, 7), (6, 7), (7, 7))
    }
  }

  "StreamSettings" should {
    "refuse windows that do not fit the sequence space and numbers that could read 00 2A or RG" in {
      an[IllegalArgumentException] should be thrownBy StreamSettings(window = 11, maxSeq = 20)
      an[IllegalArgumentException] should be thrownBy StreamSettings(window = 21, maxSeq = 41)
      an[IllegalArgumentException] should be thrownBy StreamSettings(window = 1, maxSeq = 42)
      an[IllegalArgumentException] should be thrownBy StreamSettings(window = 0, maxSeq = 20)
      an[IllegalArgumentException] should be thrownBy StreamSettings.thesis.copy(minRto = 3.seconds)
      an[IllegalArgumentException] should be thrownBy StreamSettings.thesis.copy(sendQueueLimit = 0)
      StreamSettings(window = 10, maxSeq = 20).window shouldBe 10
      StreamSettings.selectiveRepeat().maxSeq shouldBe 41
    }
  }
}
